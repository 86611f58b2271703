"""The package's architecture: layers, no import circles, and the checker's engines as leaves.

The import graph is built from the source with ``ast``: every ``import`` and
``from ... import`` statement of every module of ``desmon/`` (function-level ones
included), with ``from package import name`` resolved to the submodule
``package.name`` when there is one. Importing a submodule also runs its package's
``__init__``, but that edge is implied by Python, not written by the code, and is left
out. Two graphs: the imports that run (the bodies of ``if TYPE_CHECKING:`` left out),
and the dependencies (those bodies counted too: a type named in a signature is a
dependency all the same). The layers and the circles are checked on the dependencies:
a circle through a type-only import is a circle.
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


def _imports(tree: ast.AST, *, type_only: bool = False) -> list[ast.Import | ast.ImportFrom]:
    """Every import statement that can run (the bodies of ``if TYPE_CHECKING:`` skipped),
    or with ``type_only`` every import statement (those bodies too)."""
    out: list[ast.Import | ast.ImportFrom] = []
    todo: list[ast.AST] = [tree]
    while todo:
        node = todo.pop()
        if not type_only and isinstance(node, ast.If) and _is_type_checking(node.test):
            todo.extend(node.orelse)
            continue
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            out.append(node)
        todo.extend(ast.iter_child_nodes(node))
    return out


def _package_of(name: str) -> str:
    """The package a module's relative imports start from (a package's is itself)."""
    return name if (PACKAGE.parent / name.replace(".", "/") / "__init__.py").exists() else name.rpartition(".")[0]


def _from_base(node: ast.ImportFrom, package: str) -> str:
    """The absolute name of what ``from ... import`` imports from."""
    base = node.module or ""
    if node.level:
        anchor = package.split(".")
        anchor = anchor[: len(anchor) - (node.level - 1)]
        base = ".".join(anchor + ([base] if base else []))
    return base


def import_graph(trees: dict[str, ast.Module] | None = None, *, type_only: bool = False) -> nx.DiGraph:
    """desmon's modules and the imports between them (see the module docstring);
    ``trees``: the modules' syntax trees if already parsed; ``type_only``: the
    ``if TYPE_CHECKING:`` imports counted too (the dependencies)."""
    paths = {_module_name(p): p for p in PACKAGE.rglob("*.py")}
    graph = nx.DiGraph()
    graph.add_nodes_from(paths)
    for name, path in paths.items():
        package = _package_of(name)
        tree = trees[name] if trees is not None else ast.parse(path.read_text(), str(path))
        for node in _imports(tree, type_only=type_only):
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            else:
                base = _from_base(node, package)
                targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in paths else base for a in node.names]
            for target in targets:
                if target in paths and target != name:
                    graph.add_edge(name, target)
    return graph


def import_circles(graph: nx.DiGraph) -> list[str]:
    """Every circle of ``graph``, as ``a -> b -> a`` (from its first module in name order)."""
    rotated = [c[c.index(min(c)):] + c[: c.index(min(c))] for c in nx.simple_cycles(graph)]
    return [" -> ".join([*c, c[0]]) for c in sorted(rotated)]


@pytest.fixture(scope="module")
def sources() -> dict[str, tuple[Path, ast.Module]]:
    """Every module of desmon/ (module name -> path and syntax tree), parsed once for every rule."""
    return {_module_name(p): (p, ast.parse(p.read_text(), str(p))) for p in sorted(PACKAGE.rglob("*.py"))}


@pytest.fixture(scope="module")
def graph(sources) -> nx.DiGraph:  # type: ignore[no-untyped-def]
    """The imports that run."""
    return import_graph({name: tree for name, (_p, tree) in sources.items()})


@pytest.fixture(scope="module")
def dependencies(sources) -> nx.DiGraph:  # type: ignore[no-untyped-def]
    """The imports that run and the type-only ones (``if TYPE_CHECKING:``)."""
    return import_graph({name: tree for name, (_p, tree) in sources.items()}, type_only=True)


def test_the_import_graph_sees_function_level_and_submodule_imports(graph):
    # the checker chooses the table engine with an import inside a function, and the
    # verify command imports the engine registry with "from desmon.verify import engines"
    assert graph.has_edge(CHOOSER, "desmon.verify.table")
    assert graph.has_edge("desmon.cli.verify", "desmon.verify.engines")


def test_the_dependencies_are_the_imports_and_the_type_only_ones(graph, dependencies):
    assert set(graph.edges) <= set(dependencies.edges)
    # the public API names its verbs' types for type checkers only
    assert dependencies.has_edge("desmon", "desmon.api") and not graph.has_edge("desmon", "desmon.api")


def test_no_module_of_desmon_is_part_of_an_import_circle(dependencies):
    # a type-only import counts: two modules that name each other's types are one module
    # split in two (move the shared type down, or let the lower one own a Protocol)
    cycles = import_circles(dependencies)
    assert not cycles, "import circles (type-only imports counted):\n" + "\n".join(cycles)


#: The layer of every module of desmon, by the longest matching name: a module imports
#: only modules of lower layers (or of its own package at the same layer). README.md's
#: architecture table lists these rows; a new module must find its row here.
LAYERS = {
    "desmon.errors": 0,  # the DesmonError tree
    "desmon.progress": 0,  # the one in-place progress line
    "desmon.paths": 1,  # input and output files checked before any work
    "desmon.stats": 1,  # guaranteed statistics over independent runs: confidence sequences, sequential tests
    "desmon.model": 2,  # vocabulary and the DSL
    "desmon.repository": 3,  # the labelled property graph
    "desmon.detectors": 3,  # signal models and slip detectors
    "desmon.deployment": 4,  # the pure decisions
    "desmon.viz": 5,  # pictures of snapshots and timelines
    "desmon.sim": 6,  # engine: scripted replay and SimPy world
    "desmon.verify": 6,  # engines: checker and fuzzer
    "desmon.loader": 7,  # a scenario file run as a script (its checker bounds validated)
    "desmon.analyze": 7,  # engine: the Markov chain of the checker's transitions, solved exactly
    "desmon.estimate": 7,  # independent runs of the SimPy world until a guaranteed interval is narrow enough
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


def upward_imports(graph: nx.DiGraph) -> list[str]:
    """Every edge of ``graph`` from a module to one of its own layer (another row) or above."""
    bad = []
    for a, b in sorted(graph.edges):
        (row_a, la), (row_b, lb) = layer_of(a), layer_of(b)
        if la == lb and row_a == row_b:
            continue  # inside one row: a package's own modules
        if lb >= la:
            bad.append(f"{a} (layer {la:g}, {row_a}) imports {b} (layer {lb:g}, {row_b})")
    return bad


def test_imports_only_point_down(dependencies):
    bad = upward_imports(dependencies)
    assert not bad, "imports that do not point down (type-only imports counted):\n" + "\n".join(bad)


def test_the_layer_rule_catches_an_upward_import():
    g = nx.DiGraph([("desmon.model.scenario", "desmon.sim.world"), ("desmon.paths", "desmon.loader")])
    assert [line.split(" ", 1)[0] for line in upward_imports(g)] == ["desmon.model.scenario", "desmon.paths"]


_TYPE_ONLY_UPWARD = """
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from desmon.deployment.validity import Validity
"""


def test_the_circle_and_layer_rules_count_a_type_only_import(sources):
    # plant a type-only import of validity (layer 4) into the model's kinds (layer 2), which
    # validity imports: the imports that run see nothing, the dependencies a circle going up
    trees = {name: tree for name, (_p, tree) in sources.items()}
    trees["desmon.model.kinds"] = ast.parse(ast.unparse(trees["desmon.model.kinds"]) + _TYPE_ONLY_UPWARD)
    runs, deps = import_graph(trees), import_graph(trees, type_only=True)
    assert not runs.has_edge("desmon.model.kinds", "desmon.deployment.validity")
    assert "desmon.deployment.validity -> desmon.model.kinds -> desmon.deployment.validity" in import_circles(deps)
    assert any(line.startswith("desmon.model.kinds (layer 2") for line in upward_imports(deps))


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


def test_each_checker_engine_imports_nothing_of_another_engine(dependencies):
    assert set(ENGINES) <= set(dependencies.nodes), "an engine module is missing"
    bad = []
    for engine in ENGINES:
        reached = nx.descendants(dependencies, engine)
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


# -- the redesign's rules: no hidden wiring, small files and classes -------------------------
#
# Each rule is checked on every module of desmon/ (the same files as the import graph) and
# proved on a synthetic source that must break it: a rule that cannot fail guards nothing.

#: the longest file and the longest class of desmon/, in lines
MAX_FILE_LINES = 900
MAX_CLASS_LINES = 300
#: assignments into another module that are the library's documented recipe, not wiring:
#: importlib's "importing a source file directly" registers the module in sys.modules
ALLOWED_FOREIGN_TARGETS = ("sys.modules[",)
#: writes into another module that guard the process against a user's code, not wiring:
#: while a scenario script loads in desmon's own process, the os calls that would end that
#: process without an exception (os._exit, the exec family) raise instead, and are put back
#: after it (desmon/loader.py's _process_kept; tests/test_scenario_script.py)
ALLOWED_GUARDS = (("desmon/loader.py", "setattr(os, "),)
#: methods that change the container they are called on
MUTATORS = frozenset({
    "append", "extend", "insert", "update", "add", "clear", "pop", "popitem", "setdefault", "remove", "discard",
    "__setitem__", "__delitem__", "__setattr__", "__delattr__",
})


def test_the_rules_below_read_every_module_of_desmon(sources, graph):
    # the same files as the layer rules: the top-level modules and every subpackage's
    on_disk = {_module_name(p) for p in PACKAGE.rglob("*.py")}
    assert set(sources) == on_disk == set(graph.nodes)
    assert {"desmon.loader", "desmon.cli.options", "desmon.paths", "desmon.progress", "desmon.errors", "desmon.cli", "desmon.__main__"} <= set(sources)
    assert any(m.startswith("desmon.detectors.signals.") for m in sources)


def _root(node: ast.AST) -> str | None:
    """The name a chain ``a.b[c].d`` starts from (``a``), or None."""
    while isinstance(node, (ast.Attribute, ast.Subscript)):
        node = node.value
    return node.id if isinstance(node, ast.Name) else None


def _bound_by_import(node: ast.Import | ast.ImportFrom) -> dict[str, str]:
    """name -> what it names, for the names an import statement binds."""
    if isinstance(node, ast.Import):
        return {(a.asname or a.name.split(".")[0]): (a.name if a.asname else a.name.split(".")[0]) for a in node.names}
    base = "." * node.level + (node.module or "")
    return {(a.asname or a.name): f"{base}.{a.name}" for a in node.names}


def _is_desmon(origin: str) -> bool:
    return origin.startswith(".") or origin == "desmon" or origin.startswith("desmon.")


def _targets(node: ast.AST) -> list[ast.expr]:
    """What an assignment, augmented or annotated assignment or ``del`` writes, unpacked."""
    if isinstance(node, (ast.Assign, ast.Delete)):
        todo = list(node.targets)
    elif isinstance(node, (ast.AugAssign, ast.AnnAssign)):
        todo = [node.target]
    else:
        return []
    out: list[ast.expr] = []
    while todo:
        t = todo.pop()
        if isinstance(t, (ast.Tuple, ast.List)):
            todo.extend(t.elts)
        elif isinstance(t, ast.Starred):
            todo.append(t.value)
        else:
            out.append(t)
    return out


def _locals_of(fn: ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda) -> set[str]:
    """The names a function binds itself (parameters, plain assignments, loop and with targets),
    not counting the ones it declares global or imports."""
    a = fn.args
    names = {x.arg for x in [*a.posonlyargs, *a.args, *a.kwonlyargs, *([a.vararg] if a.vararg else []), *([a.kwarg] if a.kwarg else [])]}
    declared: set[str] = set()
    body = fn.body if isinstance(fn.body, list) else [fn.body]
    todo: list[ast.AST] = list(body)
    while todo:
        node = todo.pop()
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef, ast.Lambda)):
            if not isinstance(node, ast.Lambda):
                names.add(node.name)
            continue  # its own scope
        if isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
            names.add(node.id)
        elif isinstance(node, (ast.Global, ast.Nonlocal)):
            declared.update(node.names)
        todo.extend(ast.iter_child_nodes(node))
    return names - declared


def _own_imports(scope: ast.AST) -> dict[str, str]:
    """The names bound by the import statements of one scope (not of the functions in it)."""
    out: dict[str, str] = {}
    todo = list(ast.iter_child_nodes(scope))
    while todo:
        node = todo.pop()
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef, ast.Lambda)):
            continue
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            out.update(_bound_by_import(node))
        todo.extend(ast.iter_child_nodes(node))
    return out


def _assigned(node: ast.AST, imported: dict[str, str]) -> list[tuple[int, str]]:
    """``mod.x = ...``, ``mod.t[k] = ...``, ``del mod.x`` with ``mod`` imported."""
    out = []
    for t in _targets(node):
        root = _root(t)
        if isinstance(t, (ast.Attribute, ast.Subscript)) and root in imported:
            text = ast.unparse(t)
            if not text.startswith(ALLOWED_FOREIGN_TARGETS):
                out.append((node.lineno, f"{text} = ... ({root} is imported: {imported[root]})"))
    return out


def _set_by_call(node: ast.AST, imported: dict[str, str]) -> list[tuple[int, str]]:
    """``setattr(mod, ...)``, ``delattr``, ``object.__setattr__(mod, ...)`` with ``mod`` imported."""
    if not (isinstance(node, ast.Call) and node.args):
        return []
    f, root = node.func, _root(node.args[0])
    setter = (isinstance(f, ast.Name) and f.id in ("setattr", "delattr")) or (
        isinstance(f, ast.Attribute) and f.attr in ("__setattr__", "__delattr__") and isinstance(f.value, ast.Name) and f.value.id in ("object", "type")
    )
    return [(node.lineno, f"{ast.unparse(node)[:80]} ({root} is imported: {imported[root]})")] if setter and root in imported else []


def _changed_by_method(node: ast.AST, imported: dict[str, str]) -> list[tuple[int, str]]:
    """``mod.TABLE.update(...)`` and the like, with ``mod`` imported from desmon."""
    if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr in MUTATORS):
        return []
    receiver = node.func.value
    root = _root(receiver)
    if isinstance(receiver, (ast.Attribute, ast.Subscript)) and root in imported and _is_desmon(imported[root]):
        return [(node.lineno, f"{ast.unparse(node)[:80]} changes {ast.unparse(receiver)} ({root} is imported: {imported[root]})")]
    return []


def _foreign_writes_in(node: ast.AST, imported: dict[str, str]) -> list[tuple[int, str]]:
    """(line, what) for each write into an imported module or object at this one node."""
    return _assigned(node, imported) + _set_by_call(node, imported) + _changed_by_method(node, imported)


def foreign_writes(tree: ast.Module) -> list[tuple[int, str]]:
    """Every statement that assigns to (or deletes, setattr's, or -- for desmon's own modules --
    changes a container of) a module or object imported from another module: a module global
    reprogrammed from outside, invisible in the import graph. A name a function binds itself
    (a parameter, a local) is not the import it shadows."""
    out: list[tuple[int, str]] = []

    def visit(scope: ast.AST, imported: dict[str, str]) -> None:
        todo = list(ast.iter_child_nodes(scope))
        while todo:
            node = todo.pop()
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
                shadowed = _locals_of(node)
                inner = {k: v for k, v in imported.items() if k not in shadowed}
                visit(node, {**inner, **_own_imports(node)})
                todo.extend(d for d in getattr(node, "decorator_list", []))
                continue
            out.extend(_foreign_writes_in(node, imported))
            todo.extend(ast.iter_child_nodes(node))

    visit(tree, _own_imports(tree))
    return sorted(out)


def global_statements(tree: ast.Module) -> list[tuple[int, str]]:
    return sorted((n.lineno, "global " + ", ".join(n.names)) for n in ast.walk(tree) if isinstance(n, ast.Global))


#: reading the live call stack: code that behaves differently depending on who called it.
#: (A traceback's frames, read after an exception to name where it came from, are not.)
FRAME_ATTRIBUTES = frozenset({"_getframe", "f_back", "f_locals"})
INSPECT_STACK = frozenset({"currentframe", "stack", "getouterframes"})


def frame_reads(tree: ast.Module) -> list[tuple[int, str]]:
    out = []
    for n in ast.walk(tree):
        if isinstance(n, ast.Attribute) and (
            n.attr in FRAME_ATTRIBUTES or (n.attr in INSPECT_STACK and isinstance(n.value, ast.Name) and n.value.id == "inspect")
        ):
            out.append((n.lineno, ast.unparse(n)))
        elif isinstance(n, ast.ImportFrom) and any(a.name in FRAME_ATTRIBUTES | INSPECT_STACK for a in n.names):
            out.append((n.lineno, f"from {n.module} import " + ", ".join(a.name for a in n.names)))
    return sorted(out)


def _is_private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def private_imports(name: str, tree: ast.Module, modules: set[str]) -> list[tuple[int, str]]:
    """Every private name (a leading underscore; dunders are public) module ``name`` takes
    from another module of ``modules``: ``from m import _x``, and ``m._x`` with ``m`` a
    module it imports (``import a.m``, ``from a import m as _m``). What a module keeps
    private is its own: another module that needs it needs a public name (or the code
    moved to where it is used)."""
    package = _package_of(name)
    out: list[tuple[int, str]] = []
    bound: dict[str, str] = {}  # a local name -> the module of desmon it names
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            base = _from_base(node, package)
            for a in node.names:
                full = f"{base}.{a.name}"
                if full in modules:
                    bound[a.asname or a.name] = full
                elif base in modules and base != name and _is_private(a.name):
                    out.append((node.lineno, f"from {base} import {a.name}"))
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name in modules:
                    bound[a.asname or a.name.split(".")[0]] = a.name if a.asname else a.name.split(".")[0]
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and _is_private(node.attr):
            chain = ast.unparse(node.value)
            root, _dot, rest = chain.partition(".")
            module = bound[root] + _dot + rest if root in bound else None
            if module in modules and module != name:
                out.append((node.lineno, f"{chain}.{node.attr} (a private name of {module})"))
    return sorted(set(out))


def long_classes(tree: ast.Module, limit: int = MAX_CLASS_LINES) -> list[tuple[int, str]]:
    return sorted(
        (n.lineno, f"class {n.name}: {n.end_lineno - n.lineno + 1} lines")  # type: ignore[operator]
        for n in ast.walk(tree)
        if isinstance(n, ast.ClassDef) and n.end_lineno - n.lineno + 1 > limit  # type: ignore[operator]
    )


def _offenders(sources, rule) -> list[str]:  # type: ignore[no-untyped-def]
    return [f"{p.relative_to(ROOT).as_posix()}:{line} {what}" for _m, (p, tree) in sorted(sources.items()) for line, what in rule(tree)]


def test_no_module_assigns_to_another_modules_globals(sources):
    bad = [b for b in _offenders(sources, foreign_writes)
           if not any(b.startswith(f"{path}:") and b.split(" ", 1)[1].startswith(what) for path, what in ALLOWED_GUARDS)]
    assert not bad, "assignments into another module (pass the value as an argument or a port instead):\n" + "\n".join(bad)


def test_no_global_statement(sources):
    bad = _offenders(sources, global_statements)
    assert not bad, "global statements (keep the state in an object the caller owns):\n" + "\n".join(bad)


def test_no_frame_introspection(sources):
    bad = _offenders(sources, frame_reads)
    assert not bad, "sys._getframe and other frame reads (code must not depend on who calls it):\n" + "\n".join(bad)


def test_no_module_takes_another_modules_private_names(sources):
    modules = set(sources)
    bad = [
        f"{p.relative_to(ROOT).as_posix()}:{line} {what}"
        for name, (p, tree) in sorted(sources.items())
        for line, what in private_imports(name, tree, modules)
    ]
    assert not bad, "private names taken from another module (make the name public, or move the code to where it is used):\n" + "\n".join(bad)


def test_no_file_of_desmon_is_over_900_lines(sources):
    bad = [f"{p.relative_to(ROOT).as_posix()}: {n} lines" for p, _t in sources.values() if (n := len(p.read_text().splitlines())) > MAX_FILE_LINES]
    assert not bad, f"files over {MAX_FILE_LINES} lines (split them by responsibility):\n" + "\n".join(sorted(bad))


def test_no_class_of_desmon_is_over_300_lines(sources):
    bad = _offenders(sources, long_classes)
    assert not bad, f"classes over {MAX_CLASS_LINES} lines (compose smaller parts):\n" + "\n".join(bad)


# `import desmon.cli` and `desmon --help` loading neither networkx nor numpy (nor any engine):
# tests/test_cli_imports.py, in a fresh interpreter.


# -- each rule fails on a source that breaks it ----------------------------------------------

_BREAKS_EVERY_RULE = '''
import inspect
import sys
from desmon.deployment import validity as _validity
import desmon.deployment.placement
from desmon.model.system import PlatformState
from desmon.model.kinds import _fmt, Requirement as _Requirement, __doc__

_RECORDING = None


def wire(rec):
    global _RECORDING
    _RECORDING = rec
    _validity._observer = rec
    desmon.deployment.placement.VECTOR_MIN_PLATFORMS = 3
    setattr(_validity, "_memoise", False)
    _validity._TABLE["k"] = rec
    _validity._HOOKS.append(rec)
    del _validity._cache
    PlatformState.load = property(lambda self: 0)
    caller = inspect.currentframe().f_back
    memo = _validity._MEMO_SIZE + desmon.deployment.placement._cols_names(rec)
    return sys._getframe(1).f_globals, caller, memo


class Big:
''' + "    x = 1\n" * 301


_KEEPS_EVERY_RULE = '''
import sys
import traceback
from desmon.deployment import validity


def fine(args, name, module, validity_view):
    args.format = "png"           # a parameter, not an import
    setattr(args, name, 1)
    sys.modules[name] = module    # importlib's recipe
    sys.path.insert(0, name)      # not desmon's state
    validity = {"x": 1}           # a local that shadows the import
    validity["x"] = 2
    return validity


def reader(tb):
    # a traceback's frames, read after the exception to name the module it came from
    return [f.f_globals.get("__name__") for f, _line in traceback.walk_tb(tb)]


class Small:
    def __init__(self):
        self.state = 1
        object.__setattr__(self, "frozen", 2)
'''


def test_each_rule_catches_a_source_that_breaks_it():
    bad = ast.parse(_BREAKS_EVERY_RULE)
    writes = [what for _line, what in foreign_writes(bad)]
    assert [w.split(" ", 1)[0] for w in writes] == [
        "_validity._observer", "desmon.deployment.placement.VECTOR_MIN_PLATFORMS", "setattr(_validity,",
        "_validity._TABLE['k']", "_validity._HOOKS.append(rec)", "_validity._cache", "PlatformState.load",
    ], writes
    assert global_statements(bad) == [(13, "global _RECORDING")]
    assert [w for _l, w in frame_reads(bad)] == ["inspect.currentframe", "inspect.currentframe().f_back", "sys._getframe"]
    assert long_classes(bad) == [(27, "class Big: 302 lines")]
    modules = {"desmon.deployment.validity", "desmon.deployment.placement", "desmon.model.system", "desmon.model.kinds", "desmon.deployment"}
    taken = [w.split(" (", 1)[0] for _l, w in private_imports("desmon.sim.planted", bad, modules)]
    assert taken == [
        "from desmon.model.kinds import _fmt", "_validity._observer", "_validity._TABLE", "_validity._HOOKS", "_validity._cache",
        "_validity._MEMO_SIZE", "desmon.deployment.placement._cols_names",
    ], taken
    # a module's own private names are its own (a private alias of a public name, a dunder: no breach)
    own = [w.split(" (", 1)[0] for _l, w in private_imports("desmon.deployment.validity", bad, modules)]
    assert own == ["from desmon.model.kinds import _fmt", "desmon.deployment.placement._cols_names"], own


def test_the_rules_keep_parameters_locals_and_the_import_recipe():
    good = ast.parse(_KEEPS_EVERY_RULE)
    assert foreign_writes(good) == global_statements(good) == frame_reads(good) == long_classes(good) == []
    assert private_imports("desmon.sim.planted", good, {"desmon.deployment.validity", "desmon.deployment"}) == []
