"""Inputs that were once silently misread, each now refused where the fact is built:
rebalance without a preference, a lease and a script both driving one platform,
a platform state naming a resource or a graph twice, and a trace record's error
wrapped twice by ``desmon plot``."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest

from desmon.cli import main
from desmon.errors import ModelError, ScenarioError
from desmon.model import Platform, PlatformState, RobotBuilder, SystemModel
from desmon.model.actions import GRASP
from desmon.model.events import ActionChange, PlatformJoin, PlatformLeave, RequirementChange
from desmon.model.requirements import Capacity, DeploymentSpec, Preference
from desmon.model.scenario import Scenario, TimedEvent
from desmon.sim.replay import replay
from desmon.sim.world import Lease, Step, World
from desmon.viz.timeline import build_timeline

SPREAD = Preference("spread")


def _robot(*, rebalance: float | None = None, prefer: bool = True) -> RobotBuilder:
    """pc1 (the force sensor) and pc2; graph A on either, optionally preferring and rebalancing."""
    r = RobotBuilder("r")
    r.platform("pc1", memory=512).device("ft", kind="force_sensor")
    r.platform("pc2", memory=1024)
    with r.rpsl.perception_graph("A") as g:
        g.sensor("s", reads="force_sensor")
    spec = r.depsl.deployment_specification("A").add_constraint("capacity", "memory", 100)
    if prefer:
        spec.require(SPREAD)
    if rebalance is not None:
        spec.rebalance(rebalance)
    r.rules({"grasp": ["A"]})
    return r


# ---------------------------------------------------------------- 1. rebalance needs a preference


def _with_spec(spec: DeploymentSpec) -> SystemModel:
    """The robot's model with its specification of A replaced by ``spec`` (built directly)."""
    model = _robot(prefer=False).build()
    return dataclasses.replace(model, specs=(spec,))


def test_a_model_refuses_a_directly_built_specification_that_rebalances_without_a_preference():
    with pytest.raises(ModelError) as info:
        _with_spec(DeploymentSpec("A", (Capacity("memory", 100),), rebalance=0.2))
    message = str(info.value)
    assert "'A' rebalances (min_gain 0.2) but has no preference to score platforms by" in message
    assert "add a preference" in message and "drop rebalance" in message
    assert "\n" not in message


def test_a_model_accepts_a_directly_built_specification_that_rebalances_with_a_preference():
    model = _with_spec(DeploymentSpec("A", (Capacity("memory", 100), SPREAD), rebalance=0.2))
    assert model.spec("A").rebalance == 0.2


def test_the_dsl_and_the_model_refuse_rebalance_without_a_preference_with_one_message():
    with pytest.raises(ModelError) as dsl:
        _robot(prefer=False, rebalance=0.2).build()
    with pytest.raises(ModelError) as direct:
        _with_spec(DeploymentSpec("A", (Capacity("memory", 100),), rebalance=0.2))
    assert str(dsl.value) == str(direct.value)


def test_a_change_removing_the_last_preference_of_a_rebalancing_specification_is_played_to_the_end():
    # the specification a run derives after the change has rebalance and no preference:
    # rebalancing then does nothing, until a later change brings a preference back
    drop = RequirementChange("A", remove=(SPREAD,))
    back = RequirementChange("A", add=(SPREAD,))
    events = (ActionChange(GRASP), drop, back)
    scenario = Scenario(
        name="drop", model=_robot(rebalance=0.3).build(),
        timeline=tuple(TimedEvent(float(i + 1), ev, f"t{i + 1}") for i, ev in enumerate(events)),
    )
    rep = replay(scenario)
    assert [s.deployments for s in rep.steps] == [(("A", "pc1"),)] * 3
    assert rep.violations == []


# ---------------------------------------------------------------- 2. one master of a platform's presence


def _world(lease: Lease | None, *changes: object) -> World:
    return World(
        task=(Step(GRASP, 2.0),), horizon=100.0, lease=lease,
        changes=tuple(TimedEvent(10.0 * (i + 1), ev) for i, ev in enumerate(changes)),
    )


@pytest.mark.parametrize(
    "lease, event",
    [
        (Lease(), PlatformJoin("edge")),
        (Lease(platforms=("edge",)), PlatformJoin("edge")),
        (Lease(platforms=("cloud", "edge")), PlatformLeave("edge")),
    ],
    ids=["every-platform-join", "named-join", "named-leave"],
)
def test_a_world_refuses_a_lease_and_scripted_joins_or_leaves_of_the_same_platform(lease, event):
    with pytest.raises(ScenarioError) as info:
        _world(lease, event)
    message = str(info.value)
    assert "platform 'edge' has two masters" in message
    assert f"'{event}' at t=10" in message
    assert "let the lease drive it, or script its joins, not both" in message
    assert "\n" not in message


def test_a_world_accepts_a_lease_of_one_platform_and_scripted_joins_of_another():
    world = _world(Lease(platforms=("cloud",)), PlatformJoin("edge"), PlatformLeave("edge"))
    assert world.lease.platforms == ("cloud",) and len(world.changes) == 2


# ---------------------------------------------------------------- 3. one entry per resource and graph


PC = Platform.make("pc", memory=512, capacities={"cpu": 4})


@pytest.mark.parametrize(
    "kwargs, fragment",
    [
        ({"load": (("memory", 100.0), ("cpu", 1.0), ("memory", 400.0))}, "load names resource 'memory' 2 times (100.0 and 400.0)"),
        ({"deployed": (("A", (("memory", 10.0),)), ("A", (("memory", 20.0),)))}, "deployed names graph 'A' 2 times"),
        ({"deployed": (("A", (("memory", 10.0), ("memory", 20.0))),)}, "deployed consumption of 'A' names resource 'memory' 2 times (10.0 and 20.0)"),
    ],
    ids=["load", "deployed-graph", "consumption"],
)
def test_a_platform_state_refuses_a_resource_or_graph_named_twice(kwargs, fragment):
    with pytest.raises(ModelError) as info:
        PlatformState(PC, **kwargs)
    message = str(info.value)
    assert message.startswith("PlatformState of 'pc': ")
    assert fragment in message and "give each" in message
    assert "\n" not in message


def test_a_platform_state_with_one_entry_per_resource_and_graph_reads_each():
    s = PlatformState(
        PC, load=(("cpu", 1.0), ("memory", 100.0)),
        deployed=(("A", (("cpu", 0.5), ("memory", 10.0))), ("B", (("memory", 20.0),))),
    )
    assert (s.load_of("memory"), s.load_of("cpu")) == (100.0, 1.0)
    assert s.used_by("memory") == [("A", 10.0), ("B", 20.0)]


# ---------------------------------------------------------------- 4. a bad trace record is reported once


def _trace(path: Path) -> Path:
    """A run trace whose record 5 has a load amount that is no number."""
    records = [
        {"t": 0.0, "type": "run", "scenario": "demo", "deployer": "desmon", "horizon": 60.0,
         "platforms": {"pc": {"memory": 512}}, "graphs": {"force": {"memory": 50.0}}},
        {"t": 0.0, "type": "load", "platform": "pc", "resource": "memory", "amount": 100},
        {"t": 0.0, "type": "action", "action": "grasp", "duration": 2.0},
        {"t": 0.4, "type": "decision", "command": "start", "graph": "force", "platform": "pc", "ok": True, "issued": 0.1, "why": ""},
        {"t": 1.0, "type": "load", "platform": "pc", "resource": "memory", "amount": "lots"},
    ]
    path.write_text("".join(json.dumps(r) + "\n" for r in records), encoding="utf-8")
    return path


def test_plot_reports_a_bad_trace_record_once_naming_the_record(tmp_path, capsys):
    trace = _trace(tmp_path / "run.jsonl")
    assert main(["plot", str(trace), "-o", str(tmp_path / "run.png")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("desmon: error: trace record 5 (")
    assert "amount 'lots' is not a finite number >= 0" in err
    assert "run schema" not in err and err.count("write one with") == 1
    assert len(err.splitlines()) == 1
    assert not (tmp_path / "run.png").exists()


def test_the_timeline_raises_the_record_error_itself_not_a_wrapper(tmp_path):
    records = [json.loads(line) for line in _trace(tmp_path / "run.jsonl").read_text().splitlines()]
    with pytest.raises(ScenarioError) as info:
        build_timeline(records)
    assert str(info.value).startswith("trace record 5 (")


def test_an_initial_join_of_a_platform_the_lease_drives_is_refused():
    """The simulation kept an initially joined platform for good, while desmon analyze's
    chain leased and released it: two meanings of one scenario (the exact value then fell
    outside the simulated interval). One master of a platform's presence, as in changes=."""
    from desmon.loader import load_scenario

    base = load_scenario(str(Path(__file__).resolve().parents[1] / "scenarios" / "cloud_offload.py"))
    assert base.world.lease is not None
    with pytest.raises(ScenarioError, match="platform 'edge' has two masters of its presence: .* in the scenario's initial="):
        dataclasses.replace(base, initial=base.initial + (PlatformJoin("edge"),))
    dataclasses.replace(base, initial=base.initial)  # (without the join: accepted)
