"""desmon fuzz and the RuleBasedStateMachine: same core, same invariants, networkx repository."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings
from hypothesis.stateful import run_state_machine_as_test

from desmon.cli import main
from desmon.loader import load_scenario
from desmon.verify.fuzz import fuzz
from desmon.verify.machine import make_machine
from desmon.verify.mutants import MUTANTS

SCENARIOS = Path(__file__).resolve().parent.parent / "scenarios"


def test_fuzz_finds_paper_bug_and_rederives_shortest():
    out = fuzz(load_scenario(SCENARIOS / "migration.py"), "paper", examples=100, seed=1)
    assert out.exit_code == 1
    assert "VIOLATED" in out.text and " 1. " in out.text
    assert "the checker's shortest counterexample" in out.text


def test_fuzz_is_deterministic(capsys):
    path = str(SCENARIOS / "shared_platform.py")
    outs = []
    for _ in range(2):
        rc = main(["fuzz", path, "--deployer", "paper", "--examples", "50", "--seed", "7", "--no-progress"])
        outs.append((rc, capsys.readouterr().out))
    assert outs[0] == outs[1] and outs[0][0] == 1


def test_fuzz_passes_on_desmon(capsys):
    assert main(["fuzz", str(SCENARIOS / "coffee_handover.py"), "--examples", "40", "--seed", "0", "--no-progress"]) == 0
    assert "passed: " in capsys.readouterr().out


def test_fuzz_catches_a_mutant():
    out = fuzz(load_scenario(SCENARIOS / "coffee_handover.py"), MUTANTS["no-recheck"], examples=200, seed=0)
    assert out.exit_code == 1 and out.invariant in ("valid-or-error", "coverage")


def test_fuzz_and_the_state_machine_catch_an_invariant_broken_inside_a_reaction_and_repaired_by_its_end():
    """make-before-break starts the new instance before it stops the old one: two instances for
    a moment (single-instance, which the checker watches after every start and stop), none
    after the reaction."""
    sc = load_scenario(SCENARIOS / "migration.py")
    out = fuzz(sc, MUTANTS["make-before-break"], examples=200, seed=0)
    assert out.exit_code == 1 and out.invariant == "single-instance", out.text
    assert "during the reaction, right after `start force_slip_detector on pc2`" in out.text
    machine = make_machine(sc, MUTANTS["make-before-break"])
    with pytest.raises(AssertionError, match="single-instance: .* during the reaction, right after `start "):
        run_state_machine_as_test(
            machine, settings=settings(max_examples=100, stateful_step_count=10, deadline=None, database=None, suppress_health_check=list(HealthCheck), report_multiple_bugs=False)
        )


def test_fuzz_bad_examples(capsys):
    assert main(["fuzz", str(SCENARIOS / "coffee_handover.py"), "--examples", "0"]) == 2


@pytest.mark.parametrize("name", ["coffee_handover", "migration", "shared_platform"])
def test_state_machine_holds_for_desmon(name):
    machine = make_machine(load_scenario(SCENARIOS / f"{name}.py"), "desmon")
    run_state_machine_as_test(
        machine, settings=settings(max_examples=25, stateful_step_count=15, deadline=None, database=None, suppress_health_check=list(HealthCheck))
    )


def test_state_machine_finds_paper_bug():
    machine = make_machine(load_scenario(SCENARIOS / "migration.py"), "paper")
    with pytest.raises(AssertionError):
        run_state_machine_as_test(
            machine, settings=settings(max_examples=100, stateful_step_count=10, deadline=None, database=None, suppress_health_check=list(HealthCheck), report_multiple_bugs=False)
        )


def test_a_search_stopped_by_a_reaction_that_never_ends_keeps_the_smallest_failure_and_its_outcome(monkeypatch):
    """hypothesis's search ends at the first reaction that never ends (each try of a shrink
    would wait out the reaction limit): the smaller failure met before it is reported, as
    found, with the outcome of its own run, and is not marked as never ending itself."""
    import desmon.verify.fuzz as fz
    from desmon.deployment.guard import CRASH, DeployerFault, RanAway

    ran: list[int] = []

    def scripted(scenario, deployer, seq, enabler, faults=None):  # type: ignore[no-untyped-def]
        ran.append(len(seq))
        if len(seq) == 1:
            return ["a"], ("coverage", "nothing watches")
        fault = DeployerFault("never ends")
        fault.cause = RanAway("its code ran for over 2 s in one reaction")
        if faults is not None:
            faults.append(fault)
        return ["a", "b", "c"], (CRASH, "raised RanAway")

    monkeypatch.setattr(fz, "run_choices", scripted)
    search = fz._Sequences(None, "desmon", None, progress=False)  # type: ignore[arg-type]
    assert search.fails([(0, ())]) is True and search.smallest == [(0, ())] and not search.smallest_never_ends
    with pytest.raises(fz._NeverEnds):
        search.fails([(1, ()), (2, ()), (3, ())])
    assert search.smallest == [(0, ())] and not search.smallest_never_ends  # the smaller failure stays the one reported
    assert search.outcome_of([(0, ())]) == (["a"], ("coverage", "nothing watches")) and ran == [1, 3]  # not run again
    alone = fz._Sequences(None, "desmon", None, progress=False)  # type: ignore[arg-type]
    with pytest.raises(fz._NeverEnds):
        alone.fails([(1, ()), (2, ()), (3, ())])
    assert alone.smallest_never_ends and alone.outcome_of([(1, ()), (2, ()), (3, ())])[1][0] == CRASH
