"""The checker: one transition system explored by interchangeable engines, chosen here.

:class:`Checker` is the :class:`~desmon.verify.system.TransitionSystem` of a scenario
(its states, transitions, invariants and replay) plus the one place that picks the
engine exploring it (:meth:`Checker.run`): ``table`` (:mod:`desmon.verify.table`),
``direct`` (:mod:`desmon.verify.direct`, in worker processes with ``workers`` > 1:
:mod:`desmon.verify.parallel`), under the symmetry reduction with ``symmetry``
(:mod:`desmon.verify.symmetry`), or ``auto``. The engines share the search core
(:mod:`desmon.verify.search`: budgets, progress, the search tree and counterexample
rebuild by replay, the result) and never import one another.
"""

from __future__ import annotations

import functools
import math
import sys
import time
from types import ModuleType
from typing import Any, Iterable

from desmon.deployment.deployer import Deployer
from desmon.deployment.guard import ReactionStopped, watching
from desmon.errors import CheckerError
from desmon.model.scenario import Scenario
from desmon.verify.bounds import Bounds
from desmon.verify.direct import DirectSearch, Pool
from desmon.verify.search import HOLDS, Budget, CheckResult, ctrl_c, finish, paused_gc
from desmon.verify.system import TransitionSystem

__all__ = ["Checker", "ENGINES"]

#: How :meth:`Checker.run` computes transitions (see there).
ENGINES = ("auto", "table", "direct")


def _expansion_pool(system: TransitionSystem, workers: int) -> Pool:
    """The direct engine's worker processes (imported when a level first needs them)."""
    from desmon.verify.parallel import ExpansionPool

    return ExpansionPool(system, workers)


def _table_engine() -> ModuleType:
    """The table engine's module (imported on first use: it imports numpy)."""
    from desmon.verify import table

    return table


def _check_run_arguments(workers: int, engine: str, timeout: float | None, max_memory: float | None) -> None:
    if workers < 1:
        raise CheckerError(f"--workers must be at least 1, got {workers}")
    if engine not in ENGINES:
        raise CheckerError(f"unknown engine {engine!r}: choose one of {', '.join(ENGINES)}")
    for name, value in (("timeout", timeout), ("max-memory", max_memory)):
        if value is not None and not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            unit = "seconds" if name == "timeout" else "MB"
            raise CheckerError(f"--{name} {value!r}: give a finite number of {unit} above 0, or none for no limit")


class Checker(TransitionSystem):
    """Exhaustive BFS over a scenario's bounded environment, driving the real core."""

    def __init__(
        self,
        scenario: Scenario,
        deployer: str | Deployer = "desmon",
        *,
        invariants: Iterable[str] | None = None,
        bounds: Bounds | None = None,
        symmetry: bool = False,
    ) -> None:
        super().__init__(scenario, deployer, invariants=invariants, bounds=bounds)
        if symmetry:
            from desmon.verify.symmetry import Symmetry

            self.symmetry = Symmetry(self)

    def run(
        self,
        *,
        max_states: int | None = 2_000_000,
        max_depth: int | None = None,
        timeout: float | None = None,
        timeout_spent: float = 0.0,
        max_memory: float | None = None,
        keep_going: bool = False,
        progress: bool = False,
        progress_after: float = 1.0,
        progress_every: float = 0.5,
        workers: int = 1,
        engine: str = "auto",
        out=None,  # type: ignore[no-untyped-def]
    ) -> CheckResult:
        """Breadth-first search from the initial state.

        ``engine`` picks how transitions are computed; the result is the same:
        ``"table"`` runs the real core once per distinct reading of a reaction and
        replays it elsewhere (:mod:`desmon.verify.table`, one process, numpy);
        ``"direct"`` runs the real core on every transition (``workers`` > 1 applies to
        it); ``"auto"`` (default) takes the table engine unless symmetry reduction or
        ``workers`` > 1 is asked for, and falls back to the direct engine (saying why in
        :attr:`CheckResult.engine_note`) when the table engine cannot run the search: the
        deployer reads platform facts outside the requirement checks, uses a check's
        result as what it is not, or the model exceeds the engine's limits. The time of
        an abandoned table attempt counts in the result's time.

        The search ends INCOMPLETE, with what it explored so far, at ``max_states``
        states, at ``max_depth``, after ``timeout`` seconds (less ``timeout_spent``:
        ``desmon verify`` counts its start-up in its ``--timeout``), when its resident memory
        (with its workers' shares) exceeds ``max_memory`` MB, or on Ctrl-C (reason
        ``"interrupted"``, :attr:`CheckResult.interrupted`; a second Ctrl-C interrupts
        at once). The budgets are looked at between two expansions (direct engine) or
        two recorded runs of the core, two rounds of a tree walk and every few new states
        (table engine): a search overruns its time by a fraction of a second (see
        :class:`Budget`).

        With ``progress``, a one-line status (states, states/s, depth, transitions,
        memory and time with their budgets) is rewritten on ``out`` (stderr) every
        ``progress_every`` seconds once the run is ``progress_after`` seconds old, and
        closed with a newline at the end. ``out`` defaults to the *current* ``sys.stderr``.

        ``workers`` > 1 expands large BFS levels in that many forked worker processes
        (:mod:`desmon.verify.parallel`); the records are consumed in frontier order, so
        the result (states, transitions, counters, counterexamples) is the same for any
        number of workers.
        """
        entered = time.perf_counter()
        if out is None:
            out = sys.stderr
        _check_run_arguments(workers, engine, timeout, max_memory)
        table = None if engine == "direct" else _table_engine()  # it imports numpy: before the search's clock starts

        fresh = functools.partial(self._fresh_result, workers=workers, timeout=timeout, max_memory=max_memory)
        t0 = time.perf_counter()
        timeout_spent += t0 - entered  # (the timeout's clock started earlier)
        res = fresh()
        budget = Budget(
            t0, timeout=timeout, timeout_spent=timeout_spent, max_memory=max_memory, progress=progress, progress_after=progress_after, progress_every=progress_every, out=out,
        )
        search = dict(max_states=max_states, max_depth=max_depth, keep_going=keep_going, budget=budget)
        try:
            with ctrl_c(budget), watching(budget.spent, budget.urgent):
                why = "" if table is None else self._table_refusal(table, engine, workers)
                if why is None:
                    outcome = self._run_table(res, table_only=engine == "table", **search)
                    if isinstance(outcome, CheckResult):
                        return outcome
                    # the table engine bowed out: the direct engine, under the same budget
                    # (the abandoned attempt's time counts in the result's)
                    res, why = fresh(), outcome
                res.engine_note = why
                return self._run_direct(res, workers=workers, **search)
        except ReactionStopped as stop:  # in the initial reaction, before the search loop
            return finish(res, self, {}, budget.reason or str(stop), 0, budget)
        finally:
            budget.close()

    def _fresh_result(self, *, workers: int, timeout: float | None, max_memory: float | None) -> CheckResult:
        """A result before any search: HOLDS, nothing counted."""
        return CheckResult(
            self.scenario.name, self.deployer_name, tuple(i.name for i in self.invariants), HOLDS,
            symmetry=self.symmetry is not None, not_checked=self.not_checked, workers=workers,
            timeout=timeout, max_memory=max_memory,
        )

    def _table_refusal(self, table: ModuleType, engine: str, workers: int) -> str | None:
        """None if the table engine runs (``engine`` "table" or "auto"), else why the direct
        engine runs instead (under "auto"; "table" refuses with a CheckerError)."""
        why = table.table_unsupported(self)
        if engine == "table" and why:
            raise CheckerError(f"--engine table: {why}; use --engine direct or auto")
        if engine == "table" and workers > 1:
            raise CheckerError("--workers runs the direct engine in several processes; the table engine runs in one: drop --workers or use --engine direct")
        if why is None and workers > 1:
            why = "--workers runs the direct engine"
        return why

    def _run_direct(self, res: CheckResult, *, workers: int, budget: Budget, **search: Any) -> CheckResult:
        """The search on the direct engine (the real core on every transition)."""
        found, incomplete, depth = DirectSearch(self, res, budget=budget, workers=workers, pool=_expansion_pool, **search).run()
        return finish(res, self, found, incomplete, depth, budget)

    def _run_table(self, res: CheckResult, *, table_only: bool, budget: Budget, **search: Any) -> "CheckResult | str":
        """The search on the table engine: its result, or (``table_only`` False) why it
        could not run it, for :meth:`run` to fall back on the direct engine."""
        table_module = _table_engine()

        res.engine, res.workers = "table", 1
        try:
            with paused_gc():  # as in the direct search: it makes no cycles
                table = table_module.TableEngine(self)
                found, incomplete, depth = table.run(res, budget=budget, **search)
        except table_module.TableUnsupported as exc:
            if table_only:
                raise
            return str(exc)
        self.explored = table.explored()
        res.records = table.records
        return finish(res, self, found, incomplete, depth, budget)

    def release(self) -> None:
        """Forget the last run's states and everything the searches memoised (here, in the
        store and in its Checks port): a process about to exit then does
        not spend seconds in the cyclic garbage collector walking millions of memoised
        tuples. The checker stays usable (its next search starts cold)."""
        drop = getattr(self.explored, "release", None)
        if drop is not None:
            drop()
        self.explored = []
        self.store.checks.clear()
        self.forget()
