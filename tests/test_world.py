"""World configuration: validation, task expansion, slips, timeline-derived worlds."""

from __future__ import annotations

import pytest

from desmon.errors import ScenarioError
from desmon.model import GRASP, MOVE_BASE, RELEASE
from desmon.sim.world import Step, World, draw_slips, expand_task, in_hand
from desmon.sim.metrics import Exposure
from desmon.model.scenario import Scenario


def test_bad_values_are_one_line_errors() -> None:
    from desmon.model.cob3 import care_o_bot

    with pytest.raises(ScenarioError, match="unknown task action 'fly'"):  # actions are the model's: checked with it
        Scenario("s", care_o_bot().build(), world=World(task=(Step("fly", 1.0),), horizon=1.0))
    with pytest.raises(ScenarioError, match="task action"):
        Step("", 1.0)
    with pytest.raises(ScenarioError, match="horizon"):
        World(task=(Step(GRASP, 1.0),), horizon=-1)
    with pytest.raises(ScenarioError, match="empty"):
        World(task=(), horizon=1)


def test_repeat_and_slips_are_deterministic() -> None:
    w = World(task=(Step("idle", 5), Step(GRASP, 2), Step(MOVE_BASE, 20), Step(RELEASE, 3)), horizon=300, repeat=True, slip_rate=0.05)
    segs = expand_task(w, 300)
    assert segs[0].start == 0 and segs[-1].start < 300 and len(segs) == 40
    a, b = draw_slips(w, segs, 1), draw_slips(w, segs, 1)
    assert a == b and a != draw_slips(w, segs, 2)
    spans = in_hand(segs)
    assert all(any(s <= x.time < e for s, e, _ in spans) for x in a)


def test_exposure_accounts_warmup_between_updates() -> None:
    vf = {"g": 2.5}
    ex = Exposure(lambda g: vf.get(g, float("inf")))
    ex.set_wanted(1.0, (("g",),))
    ex.advance(4.0)
    assert ex.exposure == pytest.approx(1.5) and ex.blind == [pytest.approx(1.5)]
    ex.set_wanted(5.0, ())
    assert ex.risky == pytest.approx(4.0)


def test_exposure_keeps_the_slots_apart() -> None:
    """One covered slot does not hide an uncovered one; alternatives within a slot do."""
    vf = {"force": 0.0, "tactile": 3.0, "alt": 7.0}
    ex = Exposure(lambda g: vf.get(g, float("inf")))
    ex.set_wanted(1.0, (("force",), ("tactile",)), "grasp")  # force covered at once, tactile from 3
    ex.advance(3.0)
    ex.check(3.0)  # the owner checks at every warm-up end
    ex.advance(5.0)
    assert ex.exposure == pytest.approx(2.0) and ex.blind == [pytest.approx(2.0)]
    ex.set_wanted(5.0, (("force",), ("missing", "alt")), "move")  # the slot's alternative is valid from 7
    ex.advance(7.0)
    ex.check(7.0)
    ex.advance(8.0)
    assert ex.exposure == pytest.approx(4.0) and ex.blind == [pytest.approx(2.0), pytest.approx(2.0)]
    ex.set_wanted(8.0, (("force",), ("nothing",)), "stuck")  # never covered
    ex.close(10.0)
    assert ex.exposure == pytest.approx(6.0) and ex.risky == pytest.approx(9.0) and ex.switches == 3
    assert [(a, b, c) for a, b, c in ex.intervals] == [(1.0, 3.0, "grasp"), (5.0, 7.0, "move"), (8.0, 10.0, "stuck")]


def test_the_sim_uses_the_detectors_segment() -> None:
    from desmon.detectors.signals import Segment
    from desmon.sim import world

    assert world.Segment is Segment
    segs = expand_task(World(task=(Step(GRASP, 2), Step(MOVE_BASE, 3)), horizon=10), 10)
    assert segs == (Segment(GRASP, 0.0, 2.0), Segment(MOVE_BASE, 2.0, 3.0))


# ---------------------------------------------------------------- no signal model


def _camera_scenario(**world_kw: object) -> Scenario:
    from desmon.model import HOLD, RobotBuilder

    r = RobotBuilder("r")
    r.platform("pc", memory=512).device("cam", kind="camera").device("ft", kind="force_sensor")
    with r.rpsl.perception_graph("vision") as g:
        g.sensor("c", reads="camera")
    r.depsl.deployment_specification("vision").add_constraint("capacity", "memory", 100)
    r.rules({HOLD: "vision"})
    w = World(task=(Step(HOLD, 10.0),), horizon=10.0, **world_kw)  # type: ignore[arg-type]
    return Scenario("camera", r.build(), world=w)


def test_a_graph_without_a_signal_model_never_counts_as_monitoring() -> None:
    from desmon.sim.engine import simulate

    r = simulate(_camera_scenario())
    assert r.decisions[0]["ok"] and r.metrics["unmonitored_exposure_s"] == r.metrics["risky_time_s"] == 10.0


def test_the_metrics_list_the_graphs_without_a_signal_model() -> None:
    from desmon.sim.engine import simulate

    assert simulate(_camera_scenario()).metrics["no_signal_model"] == {"vision": ["camera"]}


def test_the_run_report_flags_a_graph_without_a_signal_model() -> None:
    from desmon.cli.run import format_summary
    from desmon.sim.engine import simulate

    assert "NO SIGNAL MODEL: vision (reads camera)" in format_summary(simulate(_camera_scenario()))


def test_a_kind_mapped_in_signal_kinds_is_monitored() -> None:
    from desmon.sim.engine import simulate

    r = simulate(_camera_scenario(signal_kinds={"camera": "wrench", "force_sensor": "wrench"}))
    assert r.metrics["no_signal_model"] == {} and r.metrics["unmonitored_exposure_s"] == 0.5  # the warm-up only


def test_a_run_without_signals_says_so_in_the_report(root) -> None:  # type: ignore[no-untyped-def]
    from desmon.loader import load_scenario
    from desmon.cli.run import format_summary
    from desmon.sim.engine import simulate

    r = simulate(load_scenario(root / "scenarios" / "shared_platform.py"))
    assert r.metrics["signals"] is False and "Signals: off (the world is derived from the scripted timeline)" in format_summary(r)
