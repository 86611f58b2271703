"""desmon.check and desmon.simulate: the library's two verbs, equal to what the commands run."""

from __future__ import annotations

from pathlib import Path

import desmon
from desmon.sim.engine import SimWorld
from desmon.verify.checker import Checker
from desmon.loader import load_scenario

SCENARIO = Path(__file__).resolve().parent.parent / "scenarios" / "coffee_handover.py"


def test_check_of_a_path_is_the_checkers_run_of_the_loaded_scenario():
    got = desmon.check(str(SCENARIO), engine="direct")
    want = Checker(load_scenario(SCENARIO)).run(engine="direct")
    assert (got.verdict, got.states, got.transitions, got.engine) == (want.verdict, want.states, want.transitions, "direct")


def test_check_names_a_deployer_and_finds_its_counterexample():
    got = desmon.check(load_scenario(SCENARIO), "mutant:raise-instead")
    assert got.verdict == "VIOLATED" and got.counterexamples


def test_simulate_is_the_sim_worlds_run_for_the_same_seed():
    got = desmon.simulate(SCENARIO, seed=3)
    want = SimWorld(load_scenario(SCENARIO), seed=3).run()
    assert got.metrics == want.metrics


def test_a_scenario_that_is_neither_a_scenario_nor_a_path_is_one_line():
    import pytest

    from desmon.errors import ScenarioError

    for verb in (desmon.check, desmon.simulate):
        with pytest.raises(ScenarioError, match=r"42 \(int\) is neither a Scenario nor the path"):
            verb(42)
        with pytest.raises(ScenarioError, match="no such scenario file"):
            verb("scenarios/no_such_scenario.py")
