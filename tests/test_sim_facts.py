"""The simulation's physical facts: what they remember never outlives a change of the world."""

from __future__ import annotations

from pathlib import Path

import pytest

from desmon.loader import load_scenario
from desmon.sim.facts import Instance, PhysicalFacts

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture
def facts() -> PhysicalFacts:
    return PhysicalFacts(load_scenario(ROOT / "scenarios" / "coffee_handover.py").model)


def _force_on(platform: str) -> Instance:
    return Instance("force_slip_detector", platform, 100.0, {"wrench": ("lwr_wrench",)}, None, 0.0)


@pytest.mark.parametrize(
    "kill",
    [
        lambda f: f.dev_ok.__setitem__("lwr_wrench", False),
        lambda f: f.dev_ok.update({"lwr_wrench": False}),
        lambda f: f.dev_ok.update(lwr_wrench=False),
        lambda f: f.up.__setitem__(f.host["lwr_wrench"], False),
        lambda f: f.up.update({f.host["lwr_wrench"]: False}),
    ],
    ids=["device-fails", "device-update", "device-update-kw", "host-down", "host-update"],
)
def test_a_detector_whose_sensor_dies_is_no_longer_readable_however_the_fact_is_written(facts, kill) -> None:
    inst = _force_on("arm_pc")
    host = facts.host["lwr_wrench"]
    assert facts.inputs_ok(inst) and facts.alive(inst)
    before = facts.state(host)
    kill(facts)
    assert not facts.inputs_ok(inst)  # the memo does not answer from before the change
    now = facts.state(host)
    assert now != before
    facts.dev_ok["lwr_wrench"] = True
    facts.up[host] = True
    assert facts.inputs_ok(inst) and facts.state(host) == before
