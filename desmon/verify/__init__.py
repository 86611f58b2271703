"""L4: the explicit-state checker and the hypothesis fuzzer, over the same deployment core.

``Checker(scenario, deployer).run()`` explores every interleaving of the scenario's
bounded environment events (:class:`Bounds`) breadth-first and checks the named
invariants of :mod:`desmon.deployment.invariants`; ``desmon.verify.strategies`` and
``desmon.verify.machine`` drive the same core with hypothesis; :class:`RepositoryRun`
replays events through it on the networkx repository (fuzzer, ``--plot``, ``--pytest``).

The names below are imported on first use, so that importing a light module of the
package (:mod:`desmon.verify.engines`, which the command line reads) loads no engine.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # pragma: no cover
    from desmon.verify.bounds import INSTANT_INVARIANTS, Bounds, levels
    from desmon.verify.checker import Checker
    from desmon.verify.replay import RepositoryRun
    from desmon.verify.search import HOLDS, INCOMPLETE, VIOLATED, CheckResult
    from desmon.verify.state import Key, StateStore
    from desmon.verify.trace import Counterexample, Step

__all__ = [
    "Bounds", "levels", "INSTANT_INVARIANTS",
    "Checker", "CheckResult", "Counterexample", "Step", "HOLDS", "VIOLATED", "INCOMPLETE",
    "Key", "StateStore", "RepositoryRun",
]

#: public name -> the module that defines it
_HOME = {
    "Bounds": "bounds", "levels": "bounds", "INSTANT_INVARIANTS": "bounds", "Checker": "checker",
    "CheckResult": "search", "HOLDS": "search", "VIOLATED": "search", "INCOMPLETE": "search",
    "Counterexample": "trace", "Step": "trace", "Key": "state", "StateStore": "state", "RepositoryRun": "replay",
}


def __getattr__(name: str) -> Any:
    home = _HOME.get(name)
    if home is None:
        raise AttributeError(f"module 'desmon.verify' has no attribute {name!r}")
    return getattr(importlib.import_module(f"desmon.verify.{home}"), name)


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
