"""L4: the explicit-state checker and the hypothesis fuzzer, over the same deployment core.

``Checker(scenario, deployer).run()`` explores every interleaving of the scenario's
bounded environment events (:class:`Bounds`) breadth-first and checks the named
invariants of :mod:`desmon.deployment.invariants`; ``desmon.verify.strategies`` and
``desmon.verify.machine`` drive the same core with hypothesis; :class:`RepositoryRun`
replays events through it on the networkx repository (fuzzer, ``--plot``, ``--pytest``).
"""

from desmon.verify.bounds import INSTANT_INVARIANTS, Bounds, levels
from desmon.verify.checker import Checker
from desmon.verify.search import HOLDS, INCOMPLETE, VIOLATED, CheckResult
from desmon.verify.replay import RepositoryRun
from desmon.verify.state import Key, StateStore
from desmon.verify.trace import Counterexample, Step

__all__ = [
    "Bounds", "levels", "INSTANT_INVARIANTS",
    "Checker", "CheckResult", "Counterexample", "Step", "HOLDS", "VIOLATED", "INCOMPLETE",
    "Key", "StateStore", "RepositoryRun",
]
