"""The direct engine: BFS running the real deployment core on every transition.

Each frontier state is expanded by :meth:`TransitionSystem.expand
<desmon.verify.system.TransitionSystem.expand>` (in this process, or for a large level
in worker processes: a pool the engine choice hands in, :mod:`desmon.verify.parallel`),
under a symmetry reduction when the system has one (:mod:`desmon.verify.symmetry`). The
search loop consumes the expansions' segments in frontier order, so every counter,
every state number and every counterexample is the same for any number of workers.
BFS keeps parent pointers labelled with (event, failed start indices) in a
:class:`~desmon.verify.search.Trail`, so every counterexample is a shortest one.
"""

from __future__ import annotations

from typing import Any, Callable, Iterable, Protocol

from desmon.model.events import Event
from desmon.verify.search import BreadthFirst, Budget, CheckResult, Record, Segment, Trail, paused_gc
from desmon.verify.state import Key
from desmon.verify.system import TransitionSystem, initial_states
from desmon.verify.trace import Counterexample

__all__ = ["DirectSearch", "PARALLEL_LEVEL", "Pool"]

#: BFS levels with at least this many states go to the worker processes (``workers`` > 1).
PARALLEL_LEVEL = 256


class Pool(Protocol):
    """Worker processes expanding a BFS level, in frontier order (:class:`desmon.verify.parallel.ExpansionPool`)."""

    levels: int

    def expand(self, frontier: list[Key]) -> Iterable[list[list[Segment]]]: ...

    def pids(self) -> list[int]: ...

    def close(self) -> float: ...


class DirectSearch(BreadthFirst):
    """One search of ``system`` on the direct engine, counting into ``res``.

    ``pool(system, workers)`` starts the worker processes the first time a level of
    :data:`PARALLEL_LEVEL` states or more comes (with ``workers`` > 1).
    """

    def __init__(
        self, system: TransitionSystem, res: CheckResult, *, max_states: int | None, max_depth: int | None, keep_going: bool,
        budget: Budget, workers: int = 1, pool: Callable[[TransitionSystem, int], Pool] | None = None,
    ) -> None:
        self.system, self.res, self.budget = system, res, budget
        self.max_states, self.max_depth = max_states, max_depth
        self.workers, self._make_pool = workers, pool
        self.pool: Pool | None = None
        # interned states: index[key] = i, keys[i] = key; parents and labels in the trail
        self.index: dict[Key, int] = {}
        self.keys: list[Key] = []
        self.trail = Trail(system, self.keys.__getitem__, keep_going)
        self.parts: dict = {}  # interned key parts, shared by every state holding them
        self.depth = self.transitions = 0
        self.incomplete = ""
        self.any_found = False
        self.count_names = res.branches.update

    def run(self) -> tuple[dict[str, Counterexample], str, int]:
        """The search: (counterexamples found, why incomplete or "", depth)."""
        roots = initial_states(self.system)
        for _fails, init, _bad in roots:
            self.index[init] = len(self.keys)
            self.keys.append(init)
        self.trail.set_roots([fails for fails, _init, _bad in roots])
        with paused_gc():
            try:
                return self._search(self.keys, [bad for _fails, _init, bad in roots])
            finally:
                self._close_pool()

    def _expansions(self, frontier: list[int]) -> Iterable[list[list[Segment]]]:
        keys = self.keys
        if self.workers > 1 and len(frontier) >= PARALLEL_LEVEL and self._make_pool is not None:
            if self.pool is None:
                self.pool = self._make_pool(self.system, self.workers)
                self.budget.pids = self.pool.pids  # their memory counts in the budget
                if hasattr(self.pool, "should_stop"):  # asked while waiting on a worker (one may be stuck in a reaction)
                    self.pool.should_stop = self.budget.urgent
            return self.pool.expand([keys[ki] for ki in frontier])
        expand, index = self.system.expand, self.index
        return (expand(keys[ki], index) for ki in frontier)

    def _close_pool(self) -> None:
        if self.pool is not None:
            self.res.peak_workers_mb = self.pool.close()
            self.res.worker_levels = self.pool.levels
            self.budget.pids = tuple

    def _level(self, frontier: list[int]) -> list[int]:
        """Consume one BFS level's expansions in frontier order; returns the next level."""
        nxt: list[int] = []
        spent = self.budget.spent
        expansions = iter(self._expansions(frontier))
        for ki in frontier:
            if self._finished():  # (asked before the next state is expanded: none is expanded in vain)
                break
            if spent():  # time, memory, Ctrl-C: looked at between two expansions
                self.incomplete = self.budget.reason
                break
            self._state(ki, next(expansions), nxt)
            if self.incomplete:
                break
        return nxt

    def _state(self, ki: int, per_event: list[list[Segment]], nxt: list[int]) -> None:
        """Consume the expansion of state ``ki``, event by event."""
        res = self.res
        key = self.keys[ki]
        res.rules[key.context] += 1
        enabled_count, changed, count_names, record = res.enabled, res.changed, self.count_names, self._record
        routines = 0  # routine transitions, added to the count at the end
        try:
            for (event, kind), segments in zip(self.system.enabled_kinds(key), per_event, strict=True):
                enabled_count[kind] += 1
                for routine, routine_moved, routine_names, rec in segments:
                    if routine:
                        routines += routine
                        if routine_moved:
                            changed[kind] += routine_moved
                        count_names(routine_names)
                    if rec is not None and record(ki, event, kind, rec, nxt):
                        break
                if (self.any_found and self.trail.done()) or self.incomplete:
                    break
        finally:
            self.transitions += routines

    def _record(self, ki: int, event: Event, kind: str, rec: Record, nxt: list[int]) -> bool:
        """Consume one record of state ``ki``'s ``event``; True if the search has what it looks for."""
        fails, ckey, moved, names, repaired, bad = rec
        self.transitions += 1
        self.count_names(names)
        if repaired and self._record_each(repaired, {f[0] for f in repaired}, ki, (event, fails)):
            return True
        if moved:
            self.res.changed[kind] += 1
        if ckey is None or ckey in self.index:
            return False
        self._add_state(self._add(ckey), ki, (event, fails), (event, fails), kind, bad, nxt)
        return False

    def _add(self, ckey: Any) -> int:
        """The number of a new state (a Key, or the plain tuple a worker sends for one)."""
        ni = len(self.keys)
        ckey = self._intern(ckey)
        self.index[ckey] = ni
        self.keys.append(ckey)
        return ni

    def _intern(self, k: tuple) -> Key:
        parts = self.parts
        return Key(
            k[0],
            parts.setdefault(k[1], k[1]),
            parts.setdefault(k[2], k[2]),
            parts.setdefault(k[3], k[3]),
            parts.setdefault(k[4], k[4]),
            parts.setdefault(k[5], k[5]),
            parts.setdefault(k[6], k[6]) if len(k) > 6 else (),
        )
