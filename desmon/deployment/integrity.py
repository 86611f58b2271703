"""Fingerprints of what a user's deployer must not change: desmon's own code and the model.

A user's deployer runs in desmon's process (in the worker process desmon supervises,
:mod:`desmon.cli.supervise`). It is handed the model's objects and could, in Python, do
anything to them and to desmon's modules. These fingerprints make such a change
visible: taken before the deployer's module is imported and again once the command's
work is done, a difference refuses the result with one line naming what changed
(docs/deployers.md, "What desmon's isolation catches").

* :func:`code_fingerprint`: for every loaded ``desmon`` module, the identity of each of
  its attributes; of a function, its code, defaults and closure too; of a class, every
  entry of its namespace (methods' code included); of a tuple, frozenset or dict, its
  items, and of a frozen record among them (an invariant), its fields. Replacing an invariant function,
  wrapping a port's method or swapping a function's ``__code__`` changes it.
* :func:`model_fingerprint`: the text of every field of the model, each platform on its
  own (raising a platform's capacities through ``object.__setattr__`` changes it).
"""

from __future__ import annotations

import dataclasses
import importlib
import sys
from types import FunctionType
from typing import Any, Iterator

__all__ = ["code_fingerprint", "changed", "model_fingerprint", "BASELINE_MODULES"]

#: desmon's modules a command's checks run in, imported before the fingerprint is taken
#: (a deployer's module that imports one of them first and changes it is caught too)
BASELINE_MODULES = (
    "desmon.deployment.core", "desmon.deployment.invariants", "desmon.deployment.ports", "desmon.deployment.validity",
    "desmon.deployment.control", "desmon.deployment.guard", "desmon.deployment.deployer", "desmon.deployment.memo",
    "desmon.deployment.placement", "desmon.deployment.monitor", "desmon.verify.system", "desmon.verify.checker",
    "desmon.verify.direct", "desmon.verify.state", "desmon.verify.search", "desmon.verify.report", "desmon.verify.fuzz",
    "desmon.verify.table", "desmon.verify.table.recording", "desmon.sim.world", "desmon.sim.driver",
)


def _function_parts(fn: Any) -> Iterator[tuple[str, int]]:
    yield "", id(fn)
    yield ".__code__", id(getattr(fn, "__code__", None))
    yield ".__defaults__", id(getattr(fn, "__defaults__", None))
    yield ".__kwdefaults__", id(getattr(fn, "__kwdefaults__", None))
    for i, cell in enumerate(getattr(fn, "__closure__", None) or ()):
        try:
            yield f".__closure__[{i}]", id(cell.cell_contents)
        except ValueError:  # an empty cell
            continue


def _parts(value: Any) -> Iterator[tuple[str, int]]:
    """(a suffix naming the part, its identity) of ``value`` and of what it holds, one level down."""
    if isinstance(value, FunctionType):
        yield from _function_parts(value)
        return
    yield "", id(value)
    if isinstance(value, type):
        for name, item in list(vars(value).items()):
            for suffix, ident in _function_parts(item) if isinstance(item, FunctionType) else (("", id(item)),):
                yield f".{name}{suffix}", ident
    elif isinstance(value, (tuple, frozenset)):
        for i, item in enumerate(value if isinstance(value, tuple) else sorted(value, key=repr)):
            yield from _item(f"[{i}]", item)
    elif isinstance(value, dict):
        for key, item in list(value.items()):
            yield from _item(f"[{key!r}]", item)


def _item(name: str, item: Any) -> Iterator[tuple[str, int]]:
    """An item of a tuple, frozenset or dict: its identity, and a record's fields (an invariant's check)."""
    yield name, id(item)
    if dataclasses.is_dataclass(item):
        for f in dataclasses.fields(item):
            yield f"{name}.{f.name}", id(getattr(item, f.name, None))


def code_fingerprint(preload: tuple[str, ...] = ()) -> dict[str, int]:
    """The identity of every part of every loaded ``desmon`` module (see the module
    docstring), after importing the modules of ``preload``."""
    for name in preload:
        importlib.import_module(name)
    out: dict[str, int] = {}
    for name, module in list(sys.modules.items()):
        if module is None or not (name == "desmon" or name.startswith("desmon.")):
            continue
        for attr, value in list(vars(module).items()):
            if attr.startswith("__") and attr.endswith("__"):
                continue
            for suffix, ident in _parts(value):
                out[f"{name}.{attr}{suffix}"] = ident
    return out


def changed(before: dict[str, Any], after: dict[str, Any]) -> str:
    """The first part of ``before`` that is different or gone in ``after``, or ""
    (parts ``after`` adds, a module imported since, are no change)."""
    for name, value in before.items():
        if after.get(name) != value:
            return name
    return ""


def model_fingerprint(model: Any) -> dict[str, str]:
    """The text of every field of ``model`` (a :class:`~desmon.model.system.SystemModel`),
    each platform on its own as ``platform NAME``."""
    out: dict[str, str] = {}
    for f in dataclasses.fields(model):
        value = getattr(model, f.name)
        if f.name == "platforms":
            for p in value:
                out[f"platform {getattr(p, 'name', '?')}"] = _text(p)
        else:
            out[f.name] = _text(value)
    return out


def _text(value: Any) -> str:
    """``repr(value)``, or what kept it from being written (a changed model may hold anything)."""
    try:
        return repr(value)
    except Exception as exc:
        return f"unprintable: {type(exc).__name__}"
