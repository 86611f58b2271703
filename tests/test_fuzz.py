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
            machine, settings=settings(max_examples=100, stateful_step_count=10, deadline=None, database=None, suppress_health_check=list(HealthCheck))
        )
