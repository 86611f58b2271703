"""Seeded mutants of the corrected deployer, each caught with a pinned shortest counterexample."""

from __future__ import annotations

from pathlib import Path

from desmon.loader import load_scenario
from desmon.model.events import ActionChange, DeviceFail, LoadChange, PlatformDown
from desmon.verify import VIOLATED, Checker
from desmon.verify.mutants import MUTANTS

SCENARIOS = Path(__file__).resolve().parent.parent / "scenarios"


def _cex(name, mutant, invariant):
    r = Checker(load_scenario(SCENARIOS / f"{name}.py"), MUTANTS[mutant], invariants=[invariant]).run()
    assert r.verdict == VIOLATED
    return r.counterexamples[0]


def test_no_recheck_after_device_loss():
    c = _cex("coffee_handover", "no-recheck", "valid-or-error")
    # the combined detector stays on torso_pc reading a broken wrench: nothing re-checks it
    assert [s.event for s in c.steps[1:]] == [ActionChange("grasp"), DeviceFail("lwr_wrench")]
    assert "combined_slip_detector is active on torso_pc" in c.message


def test_capacity_ignoring_deployed_graphs():
    c = _cex("migration", "capacity-blind", "no-overcommit")
    # the force detector's start on pc1 fails in the first reaction, so it runs on pc2; the
    # tactile one is then added to pc2 over its capacity
    assert c.initial_fails == (0,) and [s.event for s in c.steps[1:]] == [ActionChange("move_base")]
    assert "450" in c.message


def test_make_before_break_migration():
    c = _cex("migration", "make-before-break", "single-instance")
    assert c.length == 1 and c.steps[1].event == DeviceFail("wrench_1")
    assert c.during == "start force_slip_detector on pc2"


def test_stale_errors_keep_an_error_standing_while_a_fallback_serves_the_slot():
    c = _cex("fallbacks", "stale-errors", "errors-current")
    # one failed start of the combined detector: the force fallback serves, the error stays
    assert c.length == 1 and c.steps[1].event == ActionChange("grasp") and c.steps[1].failed_starts
    assert c.message == (
        "an error stands for combined_slip_detector, but its slot is served by force_slip_detector "
        "and combined_slip_detector is not active: the error is stale"
    )


def test_stale_errors_found_from_memory_pressure_alone():
    from dataclasses import replace

    scenario = load_scenario(SCENARIOS / "fallbacks.py")
    no_failures = replace(scenario, checker=replace(scenario.checker, start_failures=0, devices=()))
    r = Checker(no_failures, MUTANTS["stale-errors"], invariants=["errors-current"]).run()
    assert r.verdict == VIOLATED
    # combined on torso_pc; the load climbs 600 -> 800 MB; force serves, combined's error stays
    assert [s.event for s in r.counterexamples[0].steps[1:]] == [
        ActionChange("grasp"), LoadChange("torso_pc", 700), LoadChange("torso_pc", 800),
    ]


def test_unmutated_deployer_holds_on_the_same_scenarios():
    for name in ("coffee_handover", "migration", "fallbacks"):
        assert Checker(load_scenario(SCENARIOS / f"{name}.py")).run().verdict == "HOLDS"
