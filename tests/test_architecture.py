"""The package's architecture: layers, no import circles, and the checker's engines as leaves.

The import graph is built from the source with ``ast``: every ``import`` and
``from ... import`` statement of every module of ``desmon/`` (function-level ones
included; only the ``if TYPE_CHECKING:`` blocks, which never run, are left out), with
``from package import name`` resolved to the submodule ``package.name`` when there is
one. Importing a submodule also runs its package's ``__init__``, but that edge is
implied by Python, not written by the code, and is left out.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import networkx as nx
import pytest

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "desmon"

#: the checker's engines: each imports the search core and the layers below, never another engine
ENGINES = ("desmon.verify.direct", "desmon.verify.table", "desmon.verify.parallel", "desmon.verify.symmetry")
#: the one module that chooses among them
CHOOSER = "desmon.verify.checker"


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _imports(tree: ast.AST) -> list[ast.Import | ast.ImportFrom]:
    """Every import statement that can run (the bodies of ``if TYPE_CHECKING:`` skipped)."""
    out: list[ast.Import | ast.ImportFrom] = []
    todo: list[ast.AST] = [tree]
    while todo:
        node = todo.pop()
        if isinstance(node, ast.If) and _is_type_checking(node.test):
            todo.extend(node.orelse)
            continue
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            out.append(node)
        todo.extend(ast.iter_child_nodes(node))
    return out


def import_graph() -> nx.DiGraph:
    """desmon's modules and the imports between them (see the module docstring)."""
    paths = {_module_name(p): p for p in PACKAGE.rglob("*.py")}
    graph = nx.DiGraph()
    graph.add_nodes_from(paths)
    for name, path in paths.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        for node in _imports(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            else:
                base = node.module or ""
                if node.level:
                    anchor = package.split(".")
                    anchor = anchor[: len(anchor) - (node.level - 1)]
                    base = ".".join(anchor + ([base] if base else []))
                targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in paths else base for a in node.names]
            for target in targets:
                if target in paths and target != name:
                    graph.add_edge(name, target)
    return graph


@pytest.fixture(scope="module")
def graph() -> nx.DiGraph:
    return import_graph()


def test_the_import_graph_sees_function_level_and_submodule_imports(graph):
    # the checker chooses the table engine with an import inside a function, and the
    # package's __init__ imports the checker with "from desmon.verify.checker import ..."
    assert graph.has_edge(CHOOSER, "desmon.verify.table")
    assert graph.has_edge("desmon.verify", CHOOSER)


def test_no_module_of_desmon_is_part_of_an_import_circle(graph):
    cycles = sorted(nx.simple_cycles(graph))
    assert not cycles, "import circles:\n" + "\n".join(" -> ".join([*c, c[0]]) for c in cycles)


#: The layer of every module of desmon, by the longest matching name: a module imports
#: only modules of lower layers (or of its own package at the same layer). README.md's
#: architecture table lists these rows; a new module must find its row here.
LAYERS = {
    "desmon.errors": 0,  # the DesmonError tree
    "desmon.progress": 0,  # the one in-place progress line
    "desmon.paths": 1,  # input and output files checked before any work
    "desmon.model": 2,  # vocabulary and the DSL
    "desmon.repository": 3,  # the labelled property graph
    "desmon.detectors": 3,  # signal models and slip detectors
    "desmon.deployment": 4,  # the pure decisions
    "desmon.viz": 5,  # pictures of snapshots and timelines
    "desmon.sim": 6,  # engine: scripted replay and SimPy world
    "desmon.verify": 6,  # engines: checker and fuzzer
    "desmon.loader": 7,  # a scenario file run as a script (its checker bounds validated)
    "desmon.sweep": 8,  # Dask sweeps over the engines
    "desmon.cli.options": 9,  # command-line options shared by the commands
    "desmon.api": 9,  # the public verbs check() and simulate() over the engines
    "desmon": 10,  # the package itself: the curated public API (desmon/__init__.py)
    "desmon.cli.common": 11,  # what the commands share: exit codes, the parser, scenario and --deployer options
    "desmon.cli": 12,  # the command line: one module per command (parse, call the library, print), main()
    "desmon.__main__": 13,  # python -m desmon
}


def layer_of(module: str) -> tuple[str, float] | None:
    """``(row, layer)`` of the longest row of :data:`LAYERS` that names ``module`` or a package of it."""
    rows = [r for r in LAYERS if module == r or module.startswith(r + ".")]
    if not rows:
        return None
    row = max(rows, key=len)
    return row, LAYERS[row]


def test_every_module_of_desmon_has_a_layer(graph):
    # every module, the top-level ones included (loader, options, paths, progress, cli):
    # only the package itself matches no row but "desmon", and nothing falls through
    missing = [m for m in graph.nodes if layer_of(m) is None]
    assert not missing, f"modules without a layer (add a row to LAYERS and to README.md's table): {missing}"
    top_level = {p.stem for p in PACKAGE.glob("*.py") if p.stem != "__init__"} | {p.name for p in PACKAGE.iterdir() if (p / "__init__.py").exists()}
    assert top_level <= {r.split(".")[1] for r in LAYERS if r.count(".") == 1}, sorted(top_level)
    assert {"desmon.loader", "desmon.cli.options", "desmon.paths"} <= set(graph.nodes)


def test_imports_only_point_down(graph):
    bad = []
    for a, b in graph.edges:
        (row_a, la), (row_b, lb) = layer_of(a), layer_of(b)
        if la == lb and row_a == row_b:
            continue  # inside one row: a package's own modules
        if lb >= la:
            bad.append(f"{a} (layer {la:g}, {row_a}) imports {b} (layer {lb:g}, {row_b})")
    assert not bad, "\n".join(bad)


def test_the_layer_rule_catches_an_upward_import():
    g = nx.DiGraph([("desmon.model.scenario", "desmon.sim.world"), ("desmon.paths", "desmon.loader")])
    ups = [(a, b) for a, b in g.edges if layer_of(b)[1] >= layer_of(a)[1]]
    assert ups == list(g.edges)


@pytest.mark.parametrize("doc, heading", [("README.md", "## Architecture"), ("docs/design.md", "## 2. Layers")])
def test_the_docs_layer_tables_give_every_row_its_layer(root, doc, heading):
    section = (root / doc).read_text().split(heading, 1)[1].split("\n## ", 1)[0]
    layer_of_path = {}
    for line in section.splitlines():
        cells = line.split("|")
        if len(cells) > 3 and cells[1].strip().isdigit():
            for path in re.findall(r"`(desmon[\w/.]*)`", cells[2]):
                layer_of_path[path.removesuffix(".py").removesuffix("/__init__").rstrip("/")] = int(cells[1])
    for row, layer in LAYERS.items():
        path = row.replace(".", "/")
        assert layer_of_path.get(path) == layer, f"{doc}'s layer table gives {path} layer {layer_of_path.get(path)}, the test {layer}"


def test_each_checker_engine_imports_nothing_of_another_engine(graph):
    assert set(ENGINES) <= set(graph.nodes), "an engine module is missing"
    bad = []
    for engine in ENGINES:
        reached = nx.descendants(graph, engine)
        bad += [f"{engine} reaches {other}" for other in ENGINES if other in reached]
        if CHOOSER in reached:
            bad.append(f"{engine} reaches the engine choice {CHOOSER}")
    assert not bad, "\n".join(bad)


def test_only_the_checker_module_imports_the_table_and_parallel_engines(graph):
    # the engine choice ("auto": table, else direct; --workers; --symmetry) lives in one place
    for engine in ("desmon.verify.table", "desmon.verify.parallel", "desmon.verify.direct"):
        importers = {a for a, _b in graph.in_edges(engine)}
        assert importers <= {CHOOSER}, f"{engine} imported by {sorted(importers - {CHOOSER})}"


@pytest.mark.parametrize("name", ["robot_day", "fallbacks", "memory_pressure"])
def test_the_table_engine_explores_exactly_the_events_of_the_environment_alphabet_in_its_order(name):
    # the event alphabet has one definition (desmon.verify.environment); the table engine's
    # numeric encoding of it must enable the same events, in the same order, in every state
    import numpy as np

    from desmon.loader import load_scenario
    from desmon.verify import Checker
    from desmon.verify.environment import enabled_events

    checker = Checker(load_scenario(ROOT / "scenarios" / f"{name}.py"))
    checker.run(engine="table", max_states=3000, keep_going=True)
    engine = checker.explored._e  # the table engine of the run
    states = list(checker.explored)
    tr = engine.events.enabled(np.frombuffer(engine.codes, dtype=np.int64))
    table = [[] for _ in states]
    for pos, ev in zip(tr.pos.tolist(), tr.ev.tolist()):
        table[pos].append(engine.events.events[ev])
    assert len(states) > 50
    for key, events in zip(states, table):
        assert events == enabled_events(checker.bounds, key), key
