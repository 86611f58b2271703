"""Detector wake-up cadence is a performance knob only: quiet chunks give the same alarms and metrics."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from desmon.loader import load_scenario
from desmon.sim.engine import simulate

ROOT = Path(__file__).resolve().parents[1]


def test_quiet_chunks_give_the_same_alarms_and_metrics_as_block_by_block() -> None:
    sc = load_scenario(ROOT / "scenarios" / "robot_day.py")
    fine = dataclasses.replace(sc, world=dataclasses.replace(sc.world, quiet_block=sc.world.block))
    a = simulate(sc, "desmon", seed=2, until=900.0)
    b = simulate(fine, "desmon", seed=2, until=900.0)
    key = lambda x: (x.time, x.detector, x.direction or "")  # noqa: E731
    assert sorted(a.alarms, key=key) == sorted(b.alarms, key=key) and a.alarms
    assert a.metrics == b.metrics
    assert a.metrics["samples"] == b.metrics["samples"]
