"""Module state of desmon: a run's state lives on the run (its Guard, its arguments, its
engine's objects), never in a module global. What a module may keep across runs is
listed here, each with why: registries of kinds (filled when a kind is defined), and
nothing else. A memo lives on the run
(a MemoChecks, a ColumnMemo, an engine object), never in a module. A new module-level
container written at run time fails this test."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "desmon"

#: (module, name) -> why it may live in the module
ALLOWED = {
    ("desmon/model/events.py", "_REGISTRY"): "registry: the event kinds, filled as each is defined",
    ("desmon/model/kinds.py", "_KINDS"): "registry: the requirement kinds, filled as each is defined",
    ("desmon/verify/environment.py", "_KINDS"): "registry: the checker's kinds of variable, filled as each is defined",
    ("desmon/sim/streams.py", "_STREAMS"): "registry: the signal streams, filled as each is defined",
    ("desmon/sim/streams.py", "_FUSIONS"): "registry: the fusion detectors, filled as each is defined",
}

_MUTATORS = {"append", "extend", "add", "update", "clear", "pop", "popitem", "setdefault", "discard", "remove", "insert", "move_to_end"}
_CONTAINERS = {"dict", "list", "set", "defaultdict", "OrderedDict", "Counter", "deque", "WeakKeyDictionary", "WeakValueDictionary"}


def module_state(source: str) -> set[str]:
    """The module-level containers of ``source`` that its code writes (a method that
    mutates, an item assigned or deleted)."""
    tree = ast.parse(source)
    names: set[str] = set()
    for node in tree.body:
        target, value = None, None
        if isinstance(node, ast.Assign) and len(node.targets) == 1 and isinstance(node.targets[0], ast.Name):
            target, value = node.targets[0].id, node.value
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name) and node.value is not None:
            target, value = node.target.id, node.value
        if target is None:
            continue
        call = isinstance(value, ast.Call) and (getattr(value.func, "id", None) or getattr(value.func, "attr", None)) in _CONTAINERS
        if isinstance(value, (ast.List, ast.Dict, ast.Set)) or call:
            names.add(target)
    written: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and isinstance(node.func.value, ast.Name):
            if node.func.value.id in names and node.func.attr in _MUTATORS:
                written.add(node.func.value.id)
        targets = node.targets if isinstance(node, (ast.Assign, ast.Delete)) else [node.target] if isinstance(node, ast.AugAssign) else []
        for t in targets:
            if isinstance(t, ast.Subscript) and isinstance(t.value, ast.Name) and t.value.id in names:
                written.add(t.value.id)
    return written


def test_only_registries_live_in_modules():
    found = {
        (str(p.relative_to(ROOT)), name) for p in sorted(PACKAGE.rglob("*.py")) for name in module_state(p.read_text())
    }
    unexpected = sorted(found - set(ALLOWED))
    assert not unexpected, "module state written at run time (put it on the run: a Guard, the command's arguments, an engine object):\n" + "\n".join(
        f"{m}: {n}" for m, n in unexpected
    )
    gone = sorted(set(ALLOWED) - found)
    assert not gone, f"listed here but no longer module state, drop them from ALLOWED: {gone}"


def test_the_scan_finds_run_state_in_a_module():
    planted = "_limit = [10]\n\ndef set_limit(n):\n    _limit[0] = n\n\n_seen = {}\n\ndef note(k):\n    _seen.setdefault(k, 0)\n\nCONST = (1, 2)\n"
    assert module_state(planted) == {"_limit", "_seen"}
    assert module_state("_table = {'a': 1}\n\ndef read(k):\n    return _table[k]\n") == set()
