"""The curated public API: what `import desmon` offers is deliberate."""

import importlib
import re
from pathlib import Path

import pytest

import desmon

COFFEE = Path(__file__).resolve().parent.parent / "scenarios" / "coffee_handover.py"

PUBLIC = {
    "__version__", "DEPLOYERS", "INVARIANTS", "DeploymentCore", "check_validity", "CheckerError", "DesmonError",
    "ModelError", "NondeterminismError", "QueryError", "ScenarioError", "SignalError", "SimulationError", "EstimateError",
    "load_scenario", "RobotBuilder", "RuleTable", "SystemModel", "Scenario", "TimedEvent", "Repository",
    "RepositoryQuery", "check", "simulate",
}


def test_the_top_level_all_is_exactly_the_curated_list():
    assert set(desmon.__all__) == PUBLIC


def test_every_name_in_every_package_all_exists():
    for module in ("desmon", "desmon.model", "desmon.repository", "desmon.deployment", "desmon.errors"):
        mod = importlib.import_module(module)
        for name in mod.__all__:
            assert hasattr(mod, name), f"{module}.{name}"


def test_usage_errors_are_catchable_as_builtins():
    assert issubclass(desmon.ModelError, ValueError)
    assert issubclass(desmon.ScenarioError, ValueError)
    assert issubclass(desmon.QueryError, LookupError)
    assert issubclass(desmon.NondeterminismError, desmon.CheckerError)


def test_the_package_ships_a_py_typed_marker(root):
    assert (root / "desmon" / "py.typed").exists()



@pytest.mark.parametrize("kw, says", [
    ({"until": float("nan")}, "until = nan is not a number"), ({"until": 0}, "until = 0 is not positive"),
    ({"until": float("inf")}, "until = inf is not finite"), ({"seed": None}, "seed None: give a whole number"),
    ({"seed": 1.5}, "seed 1.5: give a whole number"), ({"seed": True}, "seed True: give a whole number"),
    ({"deployer": None}, "deployer None (NoneType): give a deployer's name or spec"),
])
def test_simulate_refuses_what_desmon_run_refuses_by_name(kw, says):
    """The API had taken until=nan (a horizon of nan), run seed 1.5 as 1 and raised simpy's
    or Python's own errors for the rest."""
    from desmon.errors import DesmonError

    with pytest.raises(DesmonError, match=re.escape(says)):
        desmon.simulate(str(COFFEE), **kw)


@pytest.mark.parametrize("kw, says", [
    ({"max_states": float("nan")}, "--max-states nan: give a whole number, 1 or more"), ({"max_states": 0}, "--max-states 0"),
    ({"max_states": True}, "--max-states True"), ({"max_states": "10"}, "--max-states '10'"), ({"max_depth": 0}, "--max-depth 0"),
    ({"keep_going": "no"}, "keep_going 'no': give True or False"), ({"bounds": 3}, "bounds 3 (int): give a desmon.verify.bounds.Bounds"),
    ({"workers": 1.5}, "--workers must be a whole number"),
])
def test_check_refuses_budgets_desmon_verify_refuses_by_name(kw, says):
    """nan had been no limit at all, 0 or True an instant INCOMPLETE, "10" a TypeError deep in the search."""
    from desmon.errors import DesmonError

    with pytest.raises(DesmonError, match=re.escape(says)):
        desmon.check(str(COFFEE), **kw)
