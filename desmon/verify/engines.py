"""The checker's engines by name: the one list ``--engine`` and :func:`~desmon.verify.checker.check` read.

:data:`REGISTRY` names each engine, where its class lives (``module:attribute``: a
class satisfying :class:`~desmon.verify.checker.Engine`) and what it does (the
``--engine`` help says it), in the order ``auto`` tries
them: the first that does not refuse a search runs it, and one that bows out during its
search (:class:`~desmon.errors.TableUnsupported`) hands the search to the next, so the
last one must accept every search. This module imports nothing, so the command line
reads the names without loading an engine; :func:`load` imports one when a search runs.
A new engine is its module and one line in :data:`REGISTRY`.
"""

from __future__ import annotations

import importlib
from typing import Any

__all__ = ["AUTO", "REGISTRY", "names", "load", "described"]

#: the choice that tries the engines of :data:`REGISTRY` in order
AUTO = "auto"
#: engine name -> (``module:attribute`` of its Engine class, what it does), in the order ``auto`` tries them
REGISTRY = {
    "table": ("desmon.verify.checker:TableEngineChoice", "run the real core once per distinct reading of a reaction and replay it "
              "(fast; not with --workers, nor for a deployer that reads platform facts outside the requirement checks)"),
    "direct": ("desmon.verify.checker:DirectEngine", "run it on every transition"),
}


def names() -> tuple[str, ...]:
    """Every ``--engine`` choice: ``auto``, then the engines in the order it tries them."""
    return (AUTO, *REGISTRY)


def load(name: str) -> Any:
    """An instance of engine ``name``'s class (its module imported now)."""
    module, _colon, attribute = REGISTRY[name][0].partition(":")
    return getattr(importlib.import_module(module), attribute)()


def described() -> str:
    """Each engine and what it does, then ``auto`` (the ``--engine`` help)."""
    each = "; ".join(f"{name}: {what}" for name, (_where, what) in REGISTRY.items())
    return f"{each}; {AUTO}: the first of them, in this order, that can run the search; the result is the same"
