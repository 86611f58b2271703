"""The curated public API: what `import desmon` offers is deliberate."""

import importlib

import desmon

PUBLIC = {
    "__version__", "DEPLOYERS", "INVARIANTS", "DeploymentCore", "check_validity", "CheckerError", "DesmonError",
    "ModelError", "NondeterminismError", "QueryError", "ScenarioError", "SignalError", "SimulationError",
    "load_scenario", "RobotBuilder", "RuleTable", "SystemModel", "Scenario", "TimedEvent", "Repository",
    "RepositoryQuery",
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


def test_lower_layers_never_import_upper_layers(root):
    order = {"errors": 0, "model": 1, "repository": 2, "detectors": 2, "deployment": 3, "sim": 4, "verify": 4, "viz": 3.5, "sweep": 4.5, "cli": 5}
    import ast

    for path in (root / "desmon").rglob("*.py"):
        rel = path.relative_to(root / "desmon")
        top = rel.parts[0].removesuffix(".py")
        if top not in order:
            continue
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            names = []
            if isinstance(node, ast.ImportFrom) and node.module:
                names = [node.module]
            elif isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            for n in names:
                parts = n.split(".")
                if parts[0] == "desmon" and len(parts) > 1 and parts[1] in order:
                    dep = parts[1]
                    assert order[dep] < order[top] or dep == top, f"{rel} imports {n}"
