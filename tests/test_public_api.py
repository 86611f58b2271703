"""The curated public API: what `import desmon` offers is deliberate."""

import importlib

import desmon

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

