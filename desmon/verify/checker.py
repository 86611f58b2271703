"""The checker: one transition system explored by interchangeable engines, chosen here.

:func:`check` explores a :class:`~desmon.verify.system.TransitionSystem` with an
:class:`Engine`: ``table`` (:mod:`desmon.verify.table`), ``direct``
(:mod:`desmon.verify.direct`, in worker processes with ``workers`` > 1:
:mod:`desmon.verify.parallel`), or ``auto``. The engines share the search core
(:mod:`desmon.verify.search`: budgets, progress, the search tree and counterexample
rebuild by replay, the result), never import one another, and keep nothing on the
system: a search's states come back on its :class:`~desmon.verify.search.CheckResult`.
A reduction (symmetry) is the system's, given to its constructor.

:class:`Checker` is the convenience most callers use: a scenario's system and the
states of its last check.
"""

from __future__ import annotations

import contextlib
import math
import sys
import time
from typing import Any, Iterable, Protocol, Sequence

from desmon.deployment.deployer import Deployer
from desmon.deployment.guard import Guard, ReactionStopped
from desmon.deployment.run import RunContext
from desmon.errors import CheckerError, ObservationConflict, TableUnsupported
from desmon.model.scenario import Scenario
from desmon.verify.bounds import Bounds, unmodelled
from desmon.verify.direct import DirectSearch, Pool
from desmon.verify.engines import AUTO, load, names
from desmon.verify.isolation import worker_pids
from desmon.verify.memory import check_memory
from desmon.verify.search import HOLDS, Budget, CheckResult, Exploration, ctrl_c, finish, paused_gc, resident_mb
from desmon.verify.state import Key
from desmon.verify.system import TransitionSystem

__all__ = ["Checker", "ENGINES", "Engine", "Exploration", "check", "release", "system_of"]

#: why ``--engine auto`` runs the direct engine when ``workers`` > 1 is asked for
_WORKERS_NOTE = "--workers runs the direct engine"

#: How :func:`check` computes transitions (see there): :func:`desmon.verify.engines.names`.
ENGINES = names()


class Engine(Protocol):
    """One way of exploring a system; every engine gives the same result."""

    name: str

    def refusal(self, system: TransitionSystem, workers: int) -> str | None:
        """Why this engine cannot run the search (None: it can)."""

    def refused(self, why: str) -> str:
        """The error when this engine, asked for by name, refuses the search (``why``: its refusal)."""

    def explore(self, system: TransitionSystem, res: CheckResult, *, budget: Budget, workers: int, fallback: bool = False,
                **search: Any) -> Exploration:
        """The search, counting into ``res`` (``search``: max_states, max_depth, keep_going);
        may raise :class:`~desmon.errors.TableUnsupported` to bow out (``fallback``: another
        engine takes the search over, so it may also bow out where it would be slow)."""


def _expansion_pool(system: TransitionSystem, workers: int) -> Pool:
    """The direct engine's worker processes (imported when a level first needs them)."""
    from desmon.verify.parallel import ExpansionPool

    return ExpansionPool(system, workers)


class DirectEngine:
    """The direct engine (:mod:`desmon.verify.direct`): the real core on every transition."""

    name = "direct"

    def refusal(self, system: TransitionSystem, workers: int) -> str | None:
        return None

    def refused(self, why: str) -> str:  # pragma: no cover - it never refuses
        return f"--engine direct: {why}"

    def explore(self, system: TransitionSystem, res: CheckResult, *, budget: Budget, workers: int, fallback: bool = False,
                **search: Any) -> Exploration:
        direct = DirectSearch(system, res, budget=budget, workers=workers, pool=_expansion_pool, **search)
        found, incomplete, depth = direct.run()
        return Exploration(found, incomplete, depth, direct.keys)


class TableEngineChoice:
    """The table engine (:mod:`desmon.verify.table`, imported on first use: numpy)."""

    name = "table"

    def refusal(self, system: TransitionSystem, workers: int) -> str | None:
        from desmon.verify.table import table_unsupported

        why = table_unsupported(system)
        if why is None and workers > 1:
            why = _WORKERS_NOTE
        return why

    def refused(self, why: str) -> str:
        if why == _WORKERS_NOTE:
            return "--workers runs the direct engine in several processes; the table engine runs in one: drop --workers or use --engine direct"
        return f"--engine table: {why}; use --engine direct or auto"

    def explore(self, system: TransitionSystem, res: CheckResult, *, budget: Budget, workers: int, fallback: bool = False,
                **search: Any) -> Exploration:
        from desmon.verify.table import TableEngine

        res.engine, res.workers = "table", 1
        with paused_gc():  # as in the direct search: it makes no cycles
            table = TableEngine(system, bow_out_on_ran_away=fallback)
            try:
                found, incomplete, depth = table.run(res, budget=budget, **search)
            except ObservationConflict as exc:
                if not fallback:
                    raise
                raise TableUnsupported(f"{exc} (as the table engine observed it; the direct engine decides)") from None
        res.records = table.records
        return Exploration(found, incomplete, depth, table.explored())


def _whole(value: object) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _check_run_arguments(workers: int, engine: str, timeout: float | None, max_memory: float | None) -> None:
    if not _whole(workers) or workers < 1:
        raise CheckerError(f"--workers must be a whole number, at least 1, got {workers!r}")
    if engine not in ENGINES:
        raise CheckerError(f"unknown engine {engine!r}: choose one of {', '.join(ENGINES)}")
    for name, value in (("timeout", timeout), ("max-memory", max_memory)):
        if value is not None and not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            unit = "seconds" if name == "timeout" else "MB"
            raise CheckerError(f"--{name} {value!r}: give a finite number of {unit} above 0, or none for no limit")


def check(
    system: TransitionSystem,
    *,
    engine: str = "auto",
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
    out: Any = None,
) -> CheckResult:
    """Breadth-first search of ``system`` from its initial state; the result carries the
    distinct states explored (:attr:`CheckResult.explored`).

    ``engine`` picks how transitions are computed; the result is the same:
    ``"table"`` runs the real core once per distinct reading of a reaction and
    replays it elsewhere (:mod:`desmon.verify.table`, one process, numpy);
    ``"direct"`` runs the real core on every transition (``workers`` > 1 applies to
    it); ``"auto"`` (default) takes the table engine (with or without symmetry
    reduction) unless ``workers`` > 1 is asked for, and falls back to the direct engine (saying why in
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
    for name, value in (("max-states", max_states), ("max-depth", max_depth)):  # (the API's: the CLI's are argparse's)
        if value is not None and not (_whole(value) and value >= 1):
            raise CheckerError(f"--{name} {value!r}: give a whole number, 1 or more, or none for no limit")
    if not isinstance(keep_going, bool):
        raise CheckerError(f"keep_going {keep_going!r}: give True or False")
    if engine != "direct":
        import desmon.verify.table  # noqa: F401  (it imports numpy: before the search's clock starts)
    t0 = time.perf_counter()
    timeout_spent += t0 - entered  # (the timeout's clock started earlier)
    res = _fresh_result(system, workers, timeout, max_memory, resident_mb() or 0.0)
    budget = Budget(
        t0, timeout=timeout, timeout_spent=timeout_spent, max_memory=max_memory, progress=progress, progress_after=progress_after, progress_every=progress_every, out=out,
    )
    budget.others = lambda: worker_pids(system.core.deployer)  # (a user's deployer's memory counts too)
    budget.start_mb = res.start_mb
    search = dict(max_states=max_states, max_depth=max_depth, keep_going=keep_going, budget=budget, workers=workers)
    try:
        with ctrl_c(budget), system.guard.watching(budget.spent, budget.urgent), system.finding_every() if keep_going else contextlib.nullcontext():
            return _search(system, engine, res, budget, search)
    except ReactionStopped as stop:  # in the initial reaction, before the search loop
        return finish(res, system, {}, budget.reason or str(stop), 0, budget)
    finally:
        budget.close()


def _drop_states(result: CheckResult) -> None:
    """Free ``result``'s states (and an engine's trees and tables) now, by reference counting."""
    drop = getattr(result.explored, "release", None)
    if drop is not None:
        drop()
    result.explored = ()


def _fresh_result(system: TransitionSystem, workers: int, timeout: float | None, max_memory: float | None, start_mb: float) -> CheckResult:
    """A result before any search: HOLDS, nothing counted."""
    return CheckResult(
        system.scenario.name, system.deployer_name, tuple(i.name for i in system.invariants), HOLDS,
        symmetry=system.symmetry is not None, not_checked=system.not_checked, unmodelled=unmodelled(system.scenario, system.bounds), workers=workers,
        timeout=timeout, max_memory=max_memory, start_mb=start_mb,
    )


#: how a refusal of the table engine ends: advice for ``--engine table``, which stops with it.
#: Under ``auto`` the direct engine has already run, and the note keeps only the reason.
_ADVICE = "; run with --engine direct"


def _reason(refusal: str) -> str:
    """``refusal`` without its closing advice to run the direct engine."""
    return refusal[: -len(_ADVICE)] if refusal.endswith(_ADVICE) else refusal


def _search(system: TransitionSystem, engine: str, res: CheckResult, budget: Budget, search: dict[str, Any]) -> CheckResult:
    """The engine asked for, or under ``auto`` the first of :data:`ENGINES` that runs the
    search, with why the ones before it did not in ``engine_note``; an engine that bows
    out during its search is dropped, and its time counts in the next one's result."""
    tried = names()[1:] if engine == AUTO else (engine,)
    why = ""
    for i, name in enumerate(tried):
        chosen: Engine = load(name)
        refusal = chosen.refusal(system, search["workers"])
        if refusal is not None:
            if engine != AUTO:
                raise CheckerError(chosen.refused(refusal))
            why = refusal
            continue
        res.engine_note = why
        try:
            fallback = engine == AUTO and i < len(tried) - 1
            return _finished(res, system, chosen.explore(system, res, fallback=fallback, **search), budget)
        except TableUnsupported as exc:
            if engine != AUTO or i == len(tried) - 1:
                raise
            res, why = _fresh_result(system, search["workers"], res.timeout, res.max_memory, res.start_mb), _reason(str(exc))
    raise CheckerError(f"no engine runs this search: {why}")  # pragma: no cover - the last engine accepts every search


def _finished(res: CheckResult, system: TransitionSystem, run: Exploration, budget: Budget) -> CheckResult:
    res.explored = run.explored
    if system.symmetry is not None:  # (the table engine counts its codes with array operations)
        count = getattr(run.explored, "states_covered", None)
        res.states_covered = count() if count is not None else system.symmetry.states_covered(run.explored)
    if _bounded_only(run.incomplete):  # a user's deployer: every reaction again, in a fresh instance
        check_memory(system)  # (also before a crash or violation it found: a deployer with memory gives neither)
    return finish(res, system, run.found, run.incomplete, run.depth, budget)


def _bounded_only(incomplete: str) -> bool:
    """Whether a search that ended so may still re-run its reactions in a fresh instance: it
    ended complete or at a state or depth cap, not at the clock, the memory budget or a Ctrl-C
    (whose time or room is spent)."""
    return not incomplete or incomplete.startswith(("max depth ", "max states "))


def system_of(
    scenario: Scenario,
    deployer: str | Deployer = "desmon",
    *,
    invariants: Iterable[str] | None = None,
    bounds: Bounds | None = None,
    symmetry: bool = False,
    guard: Guard | None = None,
    run: RunContext | None = None,
) -> TransitionSystem:
    """The transition system :func:`check` explores for ``scenario`` (``symmetry``: under
    the symmetry reduction, :mod:`desmon.verify.symmetry`; ``guard``: the run's guard,
    :mod:`desmon.deployment.guard`, its limits ``--max-commands``; ``run``: the whole run
    context instead, :mod:`desmon.deployment.run`, its guard and its memoised checks)."""
    reduction = None
    if symmetry:
        from desmon.verify.symmetry import Symmetry

        reduction = Symmetry
    return TransitionSystem(scenario, deployer, invariants=invariants, bounds=bounds, reduction=reduction, guard=guard, run=run)


def release(system: TransitionSystem, result: CheckResult | None = None) -> None:
    """Forget ``result``'s states and everything ``system``'s searches memoised (in the
    store and in its Checks port): a process about to exit then does not spend seconds
    in the cyclic garbage collector walking millions of memoised tuples. The system
    stays usable (its next search starts cold)."""
    if result is not None:
        _drop_states(result)
    system.store.checks.clear()
    system.forget()


class Checker:
    """A scenario's :class:`~desmon.verify.system.TransitionSystem` and the states of its last
    :meth:`run` (the convenience of the commands, the docs and the tests).

    Attributes it does not have are its system's (``checker.model``, ``.bounds``,
    ``.initial()``, ``.replay(...)``, ``.violations(...)``...). ``symmetry`` builds the
    system with the symmetry reduction (:mod:`desmon.verify.symmetry`).
    """

    def __init__(
        self,
        scenario: Scenario,
        deployer: str | Deployer = "desmon",
        *,
        invariants: Iterable[str] | None = None,
        bounds: Bounds | None = None,
        symmetry: bool = False,
        guard: Guard | None = None,
        run: RunContext | None = None,
    ) -> None:
        self.system = system_of(scenario, deployer, invariants=invariants, bounds=bounds, symmetry=symmetry, guard=guard, run=run)
        self._last: CheckResult | None = None

    @property
    def explored(self) -> Sequence[Key]:
        """The distinct (canonical) states of the last run, in BFS order."""
        return self._last.explored if self._last is not None else ()

    def __getattr__(self, name: str) -> Any:
        if name in ("system", "_last"):  # not set yet (unpickling, a failed constructor)
            raise AttributeError(name)
        return getattr(self.system, name)

    def run(self, **options: Any) -> CheckResult:
        """:func:`check` of the system (the same options); the states it explored are kept
        in :attr:`explored` until the next run or :meth:`release`."""
        self._last = None
        self._last = check(self.system, **options)
        return self._last

    def release(self) -> None:
        """:func:`release` of the system and the last run's states."""
        release(self.system, self._last)
        self._last = None
