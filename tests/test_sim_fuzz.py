"""Hypothesis: random fault schedules against the SimPy world; the audit must always hold
(desmon deployer), and after every reaction the repository's DEPLOYED_ON edges (read
straight off the graph, not through the Query port the audit uses) are exactly the
infrastructure's running instances, and every stop left one DEPLOYMENT_HISTORY edge."""

from __future__ import annotations

from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from desmon.loader import load_scenario
from desmon.model.events import DeviceFail, DeviceRepair, LoadChange, PlatformDown, PlatformUp
from desmon.model.scenario import Scenario, TimedEvent
from desmon.deployment.invariants import INVARIANTS
from desmon.repository import labels as L
from desmon.sim.engine import SimWorld
from desmon.sim.world import StartFailure, World

ROOT = Path(__file__).resolve().parents[1]
BASE = load_scenario(ROOT / "scenarios" / "coffee_handover.py")
DEVICES = ("lwr_wrench", "pad_thumb_prox", "pad_f1_dist")
PLATFORMS = ("torso_pc", "arm_pc", "hand_pc")

event = st.one_of(
    st.builds(DeviceFail, st.sampled_from(DEVICES)),
    st.builds(DeviceRepair, st.sampled_from(DEVICES)),
    st.builds(PlatformDown, st.sampled_from(PLATFORMS)),
    st.builds(PlatformUp, st.sampled_from(PLATFORMS)),
)
# Faults stop 5 s before the 40 s horizon, so every reaction they cause completes inside
# the run (a reaction still waiting for a start at the horizon is never settled).
timed = st.tuples(st.floats(0.0, 35.0, allow_nan=False).map(lambda x: round(x, 2)), event)
loads = st.tuples(st.floats(0.0, 35.0).map(lambda x: round(x, 2)), st.sampled_from(PLATFORMS), st.integers(0, 1000))


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    faults=st.lists(timed, max_size=8),
    load_events=st.lists(loads, max_size=4),
    seed=st.integers(0, 1000),
    p_fail=st.sampled_from([0.0, 0.3]),
)
def test_random_fault_schedules_keep_the_invariants(faults, load_events, seed, p_fail) -> None:
    from desmon.model import GRASP, HOLD, MOVE_BASE, RELEASE
    from desmon.sim.world import Step

    world = World(
        task=(Step(GRASP, 6.0), Step(HOLD, 2.0), Step(MOVE_BASE, 15.0), Step(RELEASE, 5.0), Step(GRASP, 12.0)),
        horizon=40.0,
        faults=tuple(TimedEvent(t, e) for t, e in sorted(faults, key=lambda x: x[0])),
        loads=tuple(TimedEvent(t, LoadChange(p, mb)) for t, p, mb in sorted(load_events, key=lambda x: x[0])),
        start_latency=0.3,
        start_failure=StartFailure(probability=p_fail),
        recognition_delay=0.1,
        heartbeat_timeout=0.2,
        signals=False,
    )
    sc = Scenario(name="fuzz", model=BASE.model, initial=BASE.initial, world=world)
    w = SimWorld(sc, deployer="desmon", seed=seed)
    checked = _check_after_every_reaction(w)
    r = w.run()
    assert not r.violations, r.violations
    assert checked and checked[0] == w.reactions  # every reaction was checked
    _agree(w)  # and at the horizon


def _edges(w: SimWorld, label: str) -> list[tuple[str, str]]:
    g = w.repo.graph
    return sorted((g.nodes[s]["name"], g.nodes[t]["name"]) for s, t, d in g.edges(data=True) if d["label"] == label)


def _agree(w: SimWorld) -> None:
    """The repository and the infrastructure tell the same story (the ``history`` invariant)."""
    assert _edges(w, L.DEPLOYED_ON) == sorted(w.instances)
    assert len(_edges(w, L.DEPLOYMENT_HISTORY)) == w.stops
    view = w.core.view(running=tuple(sorted(w.instances)), stops=w.stops, history=w.history_edges)
    assert INVARIANTS["history"].check(view) is None


def _check_after_every_reaction(w: SimWorld) -> list[int]:
    """Wrap ``core.settle`` (called once at the end of every reaction) with :func:`_agree`."""
    count = [0]
    settle = w.core.settle

    def checked_settle(raised):  # type: ignore[no-untyped-def]
        out = settle(raised)
        _agree(w)
        count[0] += 1
        return out

    w.core.settle = checked_settle  # type: ignore[method-assign]
    return count
