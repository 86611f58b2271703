"""The explicit-state checker: BFS over (environment event + complete reaction).

A transition is one environment event (action change, device fail/repair, platform
down/up, a load step) followed by the system's complete, deterministic reaction
computed by the real :class:`~desmon.deployment.core.DeploymentCore` (context monitor,
selector, deployer variant) over a :class:`~desmon.verify.state.StateStore`. The only
other branching is Control.start failing, bounded per transition: the reaction is
re-run with an outcome prefix, and every start beyond the prefix is a choice point.

BFS keeps parent pointers labelled with (event, failed start indices), so every
counterexample is a shortest one; traces are rebuilt by replaying the labels from the
initial state, and a replay that does not reproduce the stored key is reported as
nondeterminism of the system under test.
"""

from __future__ import annotations

import contextlib
import gc
import math
import os
import resource
import signal
import sys
import threading
import time
from array import array
from collections import Counter
from dataclasses import dataclass, field
from typing import Any, Callable, Container, Iterable, Iterator, Sequence, TextIO

from desmon.deployment.core import DeploymentCore
from desmon.deployment.deployer import Deployer
from desmon.deployment.invariants import Invariant, SystemView, check_invariants, get_invariants
from desmon.deployment.ports import RaiseError, Start, Stop
from desmon.errors import CheckerError, NondeterminismError
from desmon.model.events import (
    ActionChange, DeviceFail, DeviceRepair, Event, LoadChange, PlatformDown, PlatformUp, event_kind,
)
from desmon.model.scenario import Scenario
from desmon.verify.bounds import Bounds, bounds_of
from desmon.verify.replay import initial_reaction
from desmon.verify.state import MEMO_LIMIT, Key, StateStore

__all__ = [
    "Checker", "CheckResult", "Counterexample", "Step", "Label", "Record", "Segment", "Budget", "HOLDS", "VIOLATED", "INCOMPLETE",
    "INTERRUPTED", "EVENT_KINDS", "NOT_CHECKED", "ENGINES", "EXIT_INTERRUPTED", "resident_mb",
]

HOLDS, VIOLATED, INCOMPLETE = "HOLDS", "VIOLATED", "INCOMPLETE"
#: why a search stopped by Ctrl-C is incomplete (:attr:`CheckResult.incomplete`), and its exit
#: code (128 + SIGINT, as a shell reports it)
INTERRUPTED, EXIT_INTERRUPTED = "interrupted", 130
#: How :meth:`Checker.run` computes transitions (see there).
ENGINES = ("auto", "table", "direct")
EVENT_KINDS = ("action", "device_fail", "device_repair", "platform_down", "platform_up", "load")

#: Invariants the checker cannot evaluate, and where they are checked instead. Its states
#: keep no infrastructure running list, stop count or DEPLOYMENT_HISTORY edges (the
#: SystemView it builds leaves ``running`` / ``stops`` / ``history`` None), so ``history``
#: could never fail here: it is left out of the checked set and refused by name.
NOT_CHECKED = {"history": "sim audit and fuzz only"}

#: A transition label: the event and the indices of the Control.start calls that failed.
Label = tuple[Event, tuple[int, ...]]

#: One transition as :meth:`Checker.expand` reports it to the search loop: (failed start
#: indices, the successor's canonical key or None if already known, whether the state
#: moved, the reaction's branch names, an instantaneous violation repaired before
#: quiescence or None, the invariants a new successor violates).
Record = tuple[tuple[int, ...], "Key | None", bool, tuple[str, ...], "tuple[str, str, str] | None", tuple[tuple[str, str], ...]]

#: A run of routine transitions (only counted: how many, how many moved the state, their
#: branch names) followed by one :data:`Record`, or by None at the end of an event.
Segment = tuple[int, int, tuple[str, ...], "Record | None"]

#: BFS levels with at least this many states go to the worker processes (``workers`` > 1).
PARALLEL_LEVEL = 256

#: the branch name of a reaction that issued no command
KEPT_BRANCH = ("no command (kept)",)


def branch_name(cmd: Any, ok: bool | None) -> str:
    """The deployer branch a command stands for, as the report counts them."""
    t = type(cmd)
    if t is Start:
        return "start ok" if ok else "start failed"
    if t is Stop:
        return "stop ok" if ok else "stop failed"
    return f"error {cmd.kind}"


@dataclass(frozen=True)
class Step:
    """One step of a counterexample: the label, what changed, and the state reached."""

    index: int
    event: Event | None
    failed_starts: tuple[str, ...]
    changes: tuple[str, ...]
    key: Key
    commands: tuple[str, ...] = ()
    fail_indices: tuple[int, ...] = ()

    def title(self) -> str:
        if self.event is None:
            return "initial"
        extra = "".join(f" [{s} fails]" for s in self.failed_starts)
        return f"{self.event}{extra}"


@dataclass(frozen=True)
class Counterexample:
    invariant: str
    message: str
    steps: tuple[Step, ...]
    during: str | None = None  # the command after which an instantaneous invariant broke

    @property
    def length(self) -> int:
        """Number of events after the initial state."""
        return len(self.steps) - 1

    @property
    def events(self) -> tuple[Label, ...]:
        return tuple((s.event, s.fail_indices) for s in self.steps[1:])  # type: ignore[misc]


@dataclass
class CheckResult:
    scenario: str
    deployer: str
    invariants: tuple[str, ...]
    verdict: str
    reason: str = ""
    states: int = 0
    transitions: int = 0
    depth: int = 0
    seconds: float = 0.0
    peak_mb: float = 0.0
    counterexamples: list[Counterexample] = field(default_factory=list)
    enabled: Counter = field(default_factory=Counter)
    new_states: Counter = field(default_factory=Counter)
    changed: Counter = field(default_factory=Counter)
    rules: Counter = field(default_factory=Counter)
    branches: Counter = field(default_factory=Counter)
    symmetry: bool = False
    not_checked: tuple[str, ...] = ()  # invariants left to the sim audit and the fuzzer (NOT_CHECKED)
    workers: int = 1
    peak_workers_mb: float = 0.0  # the largest worker process's peak resident size (workers > 1)
    worker_levels: int = 0  # BFS levels the workers expanded (levels under PARALLEL_LEVEL states stay in-process)
    engine: str = "direct"  # "table" or "direct" (see Checker.run)
    records: int = 0  # table engine: real runs of the core it recorded (reactions and invariant checks)
    engine_note: str = ""  # why engine "auto" ran the direct engine
    incomplete: str = ""  # why the search stopped early ("" if it did not), whatever the verdict
    timeout: float | None = None  # the time limit it ran under (seconds)
    max_memory: float | None = None  # the memory budget it ran under (MB)

    @property
    def states_per_second(self) -> float:
        return self.states / self.seconds if self.seconds > 0 else float("inf")

    @property
    def transitions_per_second(self) -> float:
        return self.transitions / self.seconds if self.seconds > 0 else float("inf")

    @property
    def interrupted(self) -> bool:
        """Whether Ctrl-C stopped the search (the report is what it explored until then)."""
        return self.incomplete == INTERRUPTED

    @property
    def exit_code(self) -> int:
        if self.interrupted:
            return EXIT_INTERRUPTED
        return {HOLDS: 0, VIOLATED: 1, INCOMPLETE: 3}[self.verdict]


def _peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _resume_gc() -> None:
    """Turn the cyclic collector back on after a search that paused it.

    Everything the search allocated is still in the youngest generation: the first
    allocation after ``gc.enable()`` would walk it all (0.4 s after 10 s of the direct
    engine on bench_7p, time past a ``--timeout``). Freezing and unfreezing first moves
    every tracked object to the oldest generation in O(1); it is walked again only by a
    full collection, when the heap has grown by a quarter.
    """
    gc.freeze()
    gc.unfreeze()
    gc.enable()


#: How often (seconds) a search reads its resident memory (the budget and the progress line);
#: with worker processes their proportional share is read too, less often.
MEMORY_EVERY = 0.05
MEMORY_EVERY_WORKERS = 0.25

_PAGE_MB = (os.sysconf("SC_PAGE_SIZE") if hasattr(os, "sysconf") else 4096) / 2**20


def resident_mb(pid: int | str = "self") -> float | None:
    """The resident memory of process ``pid`` in MB (``/proc/<pid>/statm``), None where unreadable."""
    try:
        with open(f"/proc/{pid}/statm", "rb") as fh:
            return int(fh.read().split()[1]) * _PAGE_MB
    except (OSError, ValueError, IndexError):
        return None


def proportional_mb(pid: int | str) -> float | None:
    """Process ``pid``'s proportional share of resident memory in MB (Pss: pages shared with
    forked siblings count once in a sum), None where unreadable."""
    try:
        with open(f"/proc/{pid}/smaps_rollup", "rb") as fh:
            for line in fh:
                if line.startswith(b"Pss:"):
                    return int(line.split()[1]) / 1024.0
    except (OSError, ValueError, IndexError):
        pass
    return None


class Budget:
    """What ends a search before its caps: the time limit, the memory budget and Ctrl-C.

    Both engines call :meth:`spent` often: between two expansions (direct engine), between
    two recorded runs of the core, two rounds of a tree walk and every few new states
    (table engine). It reads the clock every time (tens of nanoseconds) and the resident
    memory every :data:`MEMORY_EVERY` seconds, and it rewrites the progress line.
    """

    def __init__(
        self,
        t0: float,
        *,
        timeout: float | None = None,
        timeout_spent: float = 0.0,
        max_memory: float | None = None,
        progress: bool = False,
        progress_after: float = 1.0,
        progress_every: float = 0.5,
        out: TextIO | None = None,
    ) -> None:
        self.t0 = t0
        self.timeout = timeout
        self.before = timeout_spent  # seconds of the timeout spent before the search started
        self.deadline = math.inf if timeout is None else t0 + timeout - timeout_spent
        self.max_memory = max_memory
        self.progress, self.progress_after, self.progress_every = progress, progress_after, progress_every
        self.out = out if out is not None else sys.stderr
        self.reason = ""  # why the search must stop ("" while it may go on)
        self.interrupted = False  # set by the Ctrl-C handler of Checker.run
        self.memory = 0.0  # the last resident memory read (MB; the workers' shares included)
        #: the worker processes whose memory counts (set by the direct engine's pool)
        self.pids: Callable[[], Iterable[int]] = tuple
        #: (states, transitions, depth) of the search so far, for the progress line
        self.status: Callable[[], tuple[int, int, int]] = lambda: (0, 0, 0)
        self._next_look = t0
        self._last_progress = -math.inf
        self._printed = 0  # length of the progress line on screen (0: none)

    def spent(self) -> str:
        """Why the search must stop now, or "" to go on."""
        if self.reason:
            return self.reason
        if self.interrupted:
            self.reason = INTERRUPTED
            return self.reason
        now = time.perf_counter()
        if now > self.deadline:
            self.reason = f"timeout {self.timeout:g}s"
        elif now >= self._next_look:
            self._look(now)
        return self.reason

    def _look(self, now: float) -> None:
        pids = list(self.pids())
        self._next_look = now + (MEMORY_EVERY_WORKERS if pids else MEMORY_EVERY)
        if self.max_memory is not None or self.progress:
            self.memory = self.measure(pids)
        if self.max_memory is not None and self.memory > self.max_memory:
            self.reason = f"memory budget {self.max_memory:g} MB reached: {self.memory:,.0f} MB resident"
        elif self.progress and now - self.t0 >= self.progress_after and now - self._last_progress >= self.progress_every:
            self._last_progress = now
            self.show(now)

    @staticmethod
    def measure(pids: Sequence[int] = ()) -> float:
        """The search's resident memory in MB: this process's, plus its workers' (then every
        process counts its proportional share, so memory they share is counted once); the
        peak resident size where ``/proc`` is not readable."""
        if pids:
            shares = [proportional_mb(p) for p in ("self", *pids)]
            if None not in shares:
                return sum(shares)  # type: ignore[arg-type]
            return sum(resident_mb(p) or 0.0 for p in ("self", *pids))
        mb = resident_mb()
        return _peak_mb() if mb is None else mb

    def show(self, now: float) -> None:
        """Rewrite the progress line: states, states/s, depth, transitions, memory and time, with their budgets."""
        states, transitions, depth = self.status()
        elapsed = now - self.t0
        rate = states / elapsed if elapsed > 0 else 0.0
        memory = f"{self.memory:,.0f} MB" + (f" of {self.max_memory:g}" if self.max_memory is not None else "")
        clock = f"{elapsed + self.before:,.0f}s" + (f" of {self.timeout:g}s" if self.timeout is not None else "")
        line = f"  {states:,} states  {rate:,.0f} states/s  depth {depth}  {transitions:,} transitions  memory {memory}  time {clock}"
        print("\r" + line.ljust(self._printed), end="", file=self.out, flush=True)
        self._printed = max(len(line), 1)

    def close(self) -> None:
        """End the progress line (if one was shown) before the report."""
        if self._printed:
            print("", file=self.out, flush=True)
            self._printed = 0


@contextlib.contextmanager
def _ctrl_c(budget: Budget) -> Iterator[None]:
    """While a search runs, a first Ctrl-C asks it to stop at its next check (and report
    what it explored); a second one interrupts at once (``KeyboardInterrupt``, which the
    engines also turn into an interrupted result). Only in the main thread, and only
    where Python's own handler is installed (a program's own handler is left alone)."""
    if threading.current_thread() is not threading.main_thread() or signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        yield
        return

    def stop(signum: int, frame: Any) -> None:
        budget.interrupted = True
        signal.signal(signal.SIGINT, signal.default_int_handler)

    signal.signal(signal.SIGINT, stop)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, signal.default_int_handler)


class Checker:
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
        self.scenario = scenario
        self.model = scenario.model
        self.bounds = bounds if bounds is not None else bounds_of(scenario)
        if bounds is not None:
            bounds.validate(scenario)
        requested = get_invariants(list(invariants) if invariants else None)  # unknown names: ModelError
        blind = [i.name for i in requested if i.name in NOT_CHECKED] if invariants else []
        if blind:
            raise CheckerError(
                f"--invariant {blind[0]}: the checker cannot evaluate it (its states keep no running list, stop count or "
                f"DEPLOYMENT_HISTORY edges); it is checked by the simulation audit (desmon run) and desmon fuzz"
            )
        self.invariants: tuple[Invariant, ...] = tuple(i for i in requested if i.name not in NOT_CHECKED)
        #: the invariants of a default (all) run that the checker leaves to the audit and fuzzer
        self.not_checked: tuple[str, ...] = () if invariants else tuple(n for n in NOT_CHECKED)
        names = {i.name for i in self.invariants}
        self.instant = tuple(i for i in get_invariants(list(self.bounds.instantaneous)) if i.name in names) if self.bounds.instantaneous else ()
        self.store = StateStore(self.model)
        self.core = DeploymentCore(self.model, self.store, self.store, deployer)
        self.deployer_name = self.core.deployer.name
        self.store.watch = self.instant
        self.store.watch_check = self._instant_check
        self._instant_memo: dict[tuple, list[tuple[str, str]]] = {}
        self._enabled_memo: dict[tuple, tuple[tuple[Event, str], ...]] = {}
        self._event_pairs: dict[Event, tuple[Event, str]] = {}  # one (event, kind) object per event
        self._frozen: dict[tuple[str, ...], frozenset[str]] = {}
        self._slots_cache: dict[str | None, tuple[tuple[str, ...], ...]] = {}
        self.symmetry = None
        if symmetry:
            from desmon.verify.symmetry import Symmetry

            self.symmetry = Symmetry(self)
        self.branches: Counter = Counter()
        #: the distinct (canonical) states of the last run, in BFS order
        self.explored: Sequence[Key] = []

    # -- the transition relation ------------------------------------------------------------
    def slots(self, context: str | None) -> tuple[tuple[str, ...], ...]:
        s = self._slots_cache.get(context)
        if s is None:
            s = self._slots_cache[context] = self.core.deployer.requested(self.model.rules.slots_for(context))
        return s

    def initial(self) -> Key:
        """The scenario's initial facts, then the system's first reaction (no start fails)."""
        st = self.store
        st.load(Key(None, (), (), (), (), ()))
        self.core.standing = frozenset()
        st.begin(())
        initial_reaction(self.core, self.scenario, self.bounds, st)  # the same as RepositoryRun's
        return st.key(self.core.standing)

    def enabled(self, key: Key) -> list[Event]:
        return [e for e, _k in self._enabled(key)]

    def _enabled(self, key: Key) -> tuple[tuple[Event, str], ...]:
        """(event, kind) of every event enabled in ``key``; memoised on the parts it reads."""
        mk = (key.context, key.failed, key.down, key.loads)
        out = self._enabled_memo.get(mk)
        if out is None:
            pairs = self._event_pairs
            out = tuple(pairs.get(e) or pairs.setdefault(e, (e, event_kind(e))) for e in self._compute_enabled(key))
            if len(self._enabled_memo) > MEMO_LIMIT:
                self._enabled_memo.clear()  # bounded: there is one entry per environment combination
            self._enabled_memo[mk] = out
        return out

    def _compute_enabled(self, key: Key) -> list[Event]:
        b = self.bounds
        out: list[Event] = [ActionChange(a) for a in b.action_moves(key.context)]
        nfail = len(key.failed) + len(key.down)
        can_fail = b.max_failures is None or nfail < b.max_failures
        for d in b.devices:
            if d in key.failed:
                if b.repair:
                    out.append(DeviceRepair(d))
            elif can_fail:
                out.append(DeviceFail(d))
        for p in b.platforms:
            if p in key.down:
                if b.repair:
                    out.append(PlatformUp(p))
            elif can_fail:
                out.append(PlatformDown(p))
        if b.loads:
            cur = {p: dict(items).get(b.load_resource, 0) for p, items in key.loads}
            for p, lv in b.loads.items():
                i = lv.index(cur.get(p, 0))
                if i + 1 < len(lv):
                    out.append(LoadChange(p, lv[i + 1], b.load_resource))
                if i > 0:
                    out.append(LoadChange(p, lv[i - 1], b.load_resource))
        return out

    def _standing(self, standing: tuple[str, ...]) -> frozenset[str]:
        f = self._frozen.get(standing)
        if f is None:
            f = self._frozen[standing] = frozenset(standing)
        return f

    def _instant_check(self) -> list[tuple[str, str]]:
        """The instantaneous invariants on the store's current facts (memoised on them)."""
        st = self.store
        standing = self.core.standing
        mk = (st.failed, st.down, st.loads, st.deployed, standing, st.ctx)
        r = self._instant_memo.get(mk)
        if r is None:
            view = SystemView(st.platform_states(), self.model.specs, standing, self.slots(st.ctx))
            if len(self._instant_memo) > MEMO_LIMIT:
                self._instant_memo.clear()
            r = self._instant_memo[mk] = check_invariants(view, self.instant)
        return r

    def run_one(self, key: Key, event: Event, prefix: tuple[bool, ...]):  # type: ignore[no-untyped-def]
        """One transition: ``event`` and the complete reaction (the real core) applied to
        ``key``, starts following ``prefix`` and succeeding beyond it.

        Returns (next key, start outcomes, StepLog, instantaneous violation or None); the
        store is left in the next state.
        """
        st = self.store
        st.load(key)
        core = self.core
        core.standing = self._standing(key.standing)
        st.begin(prefix)
        _stim, log = core.step(event, st)
        return st.key(core.standing), tuple(st.outcomes), log, st.instant

    def successors(self, key: Key, event: Event) -> Iterator[tuple[tuple[int, ...], Key, Any, tuple[str, str, str] | None]]:
        """Every (failed start indices, next key, StepLog, instantaneous violation) of ``event``.

        The one implementation of a transition's branching: the reaction is first run with
        every start succeeding; each start it issued beyond the current prefix is a choice
        point, re-run with that start failing, while fewer than ``start_failures`` failed.
        """
        run_one = self.run_one
        bound = self.bounds.start_failures
        pending: list[tuple[bool, ...]] = [()]
        while pending:
            prefix = pending.pop(0)
            nkey, outcomes, log, instant = run_one(key, event, prefix)
            fails = tuple(i for i, ok in enumerate(outcomes) if not ok) if False in outcomes else ()
            if len(fails) < bound:
                for i in range(len(prefix), len(outcomes)):
                    pending.append(outcomes[:i] + (False,))
            yield fails, nkey, log, instant

    def violations(self, key: Key) -> list[tuple[str, str]]:
        st = self.store
        st.load(key)
        view = SystemView(st.platform_states(), self.model.specs, self._standing(key.standing), self.slots(key.context))
        return check_invariants(view, self.invariants)

    # -- search -----------------------------------------------------------------------------
    def expand(self, key: Key, known: "Container[Key]") -> list[list[Segment]]:
        """Every transition out of ``key``, per enabled event (in order), as a list of :data:`Segment` tuples.

        A successor in ``known`` (or met earlier in this expansion) that broke nothing on
        the way is *routine*: only counted. Every other transition (a new successor, with
        the invariants it violates, or an instantaneous violation repaired before
        quiescence) is a :data:`Record`, and closes a segment that also counts the
        routine transitions before it. The search loop (:meth:`run`) consumes segments
        in order, in-process or from worker processes alike; since it can only stop at
        a record, it sees exactly the counts a transition-by-transition loop would.
        """
        st = self.store
        canon = self.symmetry.canon if self.symmetry is not None else None
        specs = self.model.specs
        invariants = self.invariants
        fresh: set[Key] = set()
        out: list[list[Segment]] = []
        for event, _kind in self._enabled(key):
            segments: list[Segment] = []
            n = moved = 0
            names: list[str] = []
            for fails, nkey, log, instant in self.successors(key, event):
                commands = log.commands
                here = [branch_name(cmd, ok) for cmd, ok in commands] if commands else KEPT_BRANCH
                repaired = None
                # (checked even when the search has already recorded this invariant:
                # expand knows nothing of the search, and it costs only on violations)
                if instant is not None and instant[0] not in {v for v, _m in self.violations(nkey)}:
                    repaired = instant  # broken inside the reaction, repaired before quiescence
                ckey = canon(nkey) if canon is not None else nkey
                if ckey in known or ckey in fresh:
                    if repaired is None:
                        n += 1
                        moved += nkey != key
                        names += here
                        continue
                    rec: Record = (fails, None, nkey != key, tuple(here), repaired, ())
                else:
                    fresh.add(ckey)
                    st.load(ckey)
                    view = SystemView(st.platform_states(), specs, self._standing(ckey.standing), self.slots(ckey.context))
                    rec = (fails, ckey, nkey != key, tuple(here), repaired, tuple(check_invariants(view, invariants)))
                segments.append((n, moved, tuple(names), rec))
                n = moved = 0
                names = []
            if n:
                segments.append((n, moved, tuple(names), None))
            out.append(segments)
        return out

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
        if workers < 1:
            raise CheckerError(f"--workers must be at least 1, got {workers}")
        if engine not in ENGINES:
            raise CheckerError(f"unknown engine {engine!r}: choose one of {', '.join(ENGINES)}")
        for name, value in (("timeout", timeout), ("max-memory", max_memory)):
            if value is not None and not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                unit = "seconds" if name == "timeout" else "MB"
                raise CheckerError(f"--{name} {value!r}: give a finite number of {unit} above 0, or none for no limit")
        if engine != "direct":
            from desmon.verify.table import table_unsupported  # imports numpy: before the search's clock starts

        def fresh() -> CheckResult:
            return CheckResult(
                self.scenario.name, self.deployer_name, tuple(i.name for i in self.invariants), HOLDS,
                symmetry=self.symmetry is not None, not_checked=self.not_checked, workers=workers,
                timeout=timeout, max_memory=max_memory,
            )

        t0 = time.perf_counter()
        timeout_spent += t0 - entered  # (the timeout's clock started earlier)
        res = fresh()
        budget = Budget(
            t0, timeout=timeout, timeout_spent=timeout_spent, max_memory=max_memory, progress=progress, progress_after=progress_after, progress_every=progress_every, out=out,
        )
        search = dict(max_states=max_states, max_depth=max_depth, keep_going=keep_going, budget=budget)
        try:
            with _ctrl_c(budget):
                if engine != "direct":
                    why = table_unsupported(self)
                    if engine == "table" and why:
                        raise CheckerError(f"--engine table: {why}; use --engine direct or auto")
                    if engine == "table" and workers > 1:
                        raise CheckerError("--workers runs the direct engine in several processes; the table engine runs in one: drop --workers or use --engine direct")
                    if why is None and workers > 1:
                        why = "--workers runs the direct engine"
                    if why is None:
                        outcome = self._run_table(res, table_only=engine == "table", **search)
                        if isinstance(outcome, CheckResult):
                            return outcome
                        # the table engine bowed out: the direct engine, under the same budget
                        # (the abandoned attempt's time counts in the result's)
                        res, why = fresh(), outcome
                    res.engine_note = why or ""
                return self._run_direct(res, workers=workers, **search)
        finally:
            budget.close()

    def _run_direct(
        self, res: CheckResult, *, max_states: int | None, max_depth: int | None, keep_going: bool, budget: Budget, workers: int,
    ) -> CheckResult:
        """The search on the direct engine (the real core on every transition)."""
        canon = self.symmetry.canon if self.symmetry is not None else None
        init = self.initial()
        if canon is not None:
            init = canon(init)
        # interned states: index[key] = i, keys[i] = key, parent[i] / label[i] as ints
        index: dict[Key, int] = {init: 0}
        keys: list[Key] = [init]
        parent = array("l", [-1])
        label = array("l", [-1])
        labels: list[Label] = []
        label_ids: dict[Label, int] = {}
        parts: dict = {}  # interned key parts, shared by every state holding them
        found: dict[str, Counterexample] = {}
        wanted = {i.name for i in self.invariants}
        frontier = [0]
        depth = 0
        transitions = 0
        incomplete = ""
        spent = budget.spent
        budget.status = lambda: (len(keys), transitions, depth)
        rules = res.rules
        branches = res.branches
        enabled_count = res.enabled
        changed = res.changed
        new_states = res.new_states
        enabled_of = self._enabled
        expand = self.expand
        count_names = branches.update

        def path(i: int) -> tuple[list[Label], list[Key]]:
            ls: list[Label] = []
            ks: list[Key] = []
            while i >= 0:
                ks.append(keys[i])
                if label[i] >= 0:
                    ls.append(labels[label[i]])
                i = parent[i]
            ls.reverse()
            ks.reverse()
            return ls, ks

        def record(name: str, msg: str, i: int, during: str | None = None, extra: Label | None = None) -> None:
            if name in found:
                return
            ls, ks = path(i)
            if extra is not None:
                ls.append(extra)
            found[name] = Counterexample(name, msg, tuple(self.replay(ls, expect=ks)), during)

        def done() -> bool:
            return (not keep_going and bool(found)) or wanted <= set(found)

        def intern(k: tuple) -> Key:  # a Key, or the plain tuple a worker sends for one
            return Key(
                k[0],
                parts.setdefault(k[1], k[1]),
                parts.setdefault(k[2], k[2]),
                parts.setdefault(k[3], k[3]),
                parts.setdefault(k[4], k[4]),
                parts.setdefault(k[5], k[5]),
            )

        for name, msg in self.violations(init):
            record(name, msg, 0)
        any_found = bool(found)
        pool = None
        # The search makes no reference cycles (tests/test_verify.py checks it), but the
        # cyclic collector would still walk the millions of keys it holds again and again
        # (a third of the time at 80,000 states): it is paused for the search.
        collecting = gc.isenabled()
        gc.disable()
        try:
            while frontier and not (any_found and done()) and not incomplete:
                if max_depth is not None and depth >= max_depth:
                    incomplete = f"max depth {max_depth} reached with {len(frontier)} states unexplored"
                    break
                nxt: list[int] = []
                if workers > 1 and len(frontier) >= PARALLEL_LEVEL:
                    if pool is None:
                        from desmon.verify.parallel import ExpansionPool

                        pool = ExpansionPool(self, workers)
                        budget.pids = pool.pids  # their memory counts in the budget
                    expansions: Iterable[list[list[Segment]]] = pool.expand([keys[ki] for ki in frontier])
                else:
                    expansions = (expand(keys[ki], index) for ki in frontier)
                for ki, per_event in zip(frontier, expansions):
                    if any_found and done():
                        break
                    if spent():  # time, memory, Ctrl-C: looked at between two expansions
                        incomplete = budget.reason
                        break
                    key = keys[ki]
                    rules[key.context] += 1
                    for (event, kind), segments in zip(enabled_of(key), per_event, strict=True):
                        enabled_count[kind] += 1
                        for routine, routine_moved, routine_names, rec in segments:
                            if routine:
                                transitions += routine
                                if routine_moved:
                                    changed[kind] += routine_moved
                                count_names(routine_names)
                            if rec is None:
                                continue
                            fails, ckey, moved, names, repaired, bad = rec
                            transitions += 1
                            count_names(names)
                            if repaired is not None and repaired[0] not in found:
                                record(repaired[0], repaired[1], ki, repaired[2], (event, fails))
                                any_found = True
                                if done():
                                    break
                            if moved:
                                changed[kind] += 1
                            if ckey is None or ckey in index:
                                continue
                            ni = len(keys)
                            ckey = intern(ckey)
                            index[ckey] = ni
                            keys.append(ckey)
                            parent.append(ki)
                            lab = (event, fails)
                            li = label_ids.get(lab)
                            if li is None:
                                li = label_ids[lab] = len(labels)
                                labels.append(lab)
                            label.append(li)
                            new_states[kind] += 1
                            if max_states is not None and len(keys) >= max_states:
                                incomplete = f"max states {max_states:,} reached"
                            if bad:
                                for name, msg in bad:
                                    record(name, msg, ni)
                                any_found = True
                                continue  # do not explore beyond a violation
                            nxt.append(ni)
                        if (any_found and done()) or incomplete:
                            break
                    if incomplete:
                        break
                if nxt:
                    depth += 1
                frontier = nxt
        except KeyboardInterrupt:  # a second Ctrl-C (or one the handler could not catch)
            incomplete = INTERRUPTED
            n = min(len(keys), len(parent), len(label))  # a state half-added when it came
            del keys[n:], parent[n:], label[n:]
        finally:
            if pool is not None:
                res.peak_workers_mb = pool.close()
                res.worker_levels = pool.levels
                budget.pids = tuple
            if collecting:
                _resume_gc()
        self.explored = keys  # the distinct (canonical) states of the last run, BFS order
        res.states = len(keys)
        res.transitions = transitions
        return self._finish(res, found, incomplete, depth, budget)

    def _run_table(self, res: CheckResult, *, table_only: bool, budget: Budget, **search: Any) -> "CheckResult | str":
        """The search on the table engine: its result, or (``table_only`` False) why it
        could not run it, for :meth:`run` to fall back on the direct engine."""
        from desmon.verify.table import TableEngine, TableUnsupported

        res.engine, res.workers = "table", 1
        collecting = gc.isenabled()
        gc.disable()  # as in the direct search: it makes no cycles
        try:
            table = TableEngine(self)
            found, incomplete, depth = table.run(res, budget=budget, **search)
        except TableUnsupported as exc:
            if table_only:
                raise
            return str(exc)
        finally:
            if collecting:
                _resume_gc()
        self.explored = table.explored()
        res.records = table.records
        return self._finish(res, found, incomplete, depth, budget)

    def _finish(self, res: CheckResult, found: dict[str, Counterexample], incomplete: str, depth: int, budget: Budget) -> CheckResult:
        """Verdict, depth, time and memory of a finished search (either engine)."""
        res.depth = max([depth] + [c.length for c in found.values()])
        res.seconds = time.perf_counter() - budget.t0
        res.peak_mb = _peak_mb()
        res.incomplete = incomplete
        res.counterexamples = [found[i.name] for i in self.invariants if i.name in found]
        if res.counterexamples:
            res.verdict = VIOLATED
            res.reason = ", ".join(c.invariant for c in res.counterexamples)
            if incomplete:
                res.reason += f" (search incomplete: {incomplete})"
        elif incomplete:
            res.verdict, res.reason = INCOMPLETE, incomplete
        return res

    def release(self) -> None:
        """Forget the last run's states and everything the searches memoised (here, in the
        store and in :mod:`desmon.deployment.validity`): a process about to exit then does
        not spend seconds in the cyclic garbage collector walking millions of memoised
        tuples. The checker stays usable (its next search starts cold)."""
        from desmon.deployment import validity

        drop = getattr(self.explored, "release", None)
        if drop is not None:
            drop()
        self.explored = []
        self._instant_memo.clear()
        self._enabled_memo.clear()
        self.store = StateStore(self.model)
        self.core = DeploymentCore(self.model, self.store, self.store, self.core.deployer)
        self.store.watch = self.instant
        self.store.watch_check = self._instant_check
        validity.clear_memos()

    # -- traces ------------------------------------------------------------------------------
    def replay(self, labels: list[Label], expect: list[Key] | None = None) -> list[Step]:
        """Rebuild the states of ``labels`` from the initial state (the trace); checks determinism."""
        key = self.initial()
        if self.symmetry is not None:
            return self.symmetry.replay(labels, expect)
        if expect and key != expect[0]:
            raise NondeterminismError(f"the initial reaction is not deterministic: got {key}, stored {expect[0]}")
        steps = [Step(0, None, (), describe_state(key), key)]
        for i, (event, fails) in enumerate(labels, 1):
            prefix = tuple(j not in fails for j in range(max(fails) + 1)) if fails else ()
            prev = key
            key, _outcomes, log, _instant = self.run_one(prev, event, prefix)
            if expect is not None and i < len(expect) and key != expect[i]:
                raise NondeterminismError(
                    f"replaying step {i} ({event}) did not reproduce the stored state: the system under test is nondeterministic\n"
                    f"  stored:   {expect[i]}\n  replayed: {key}"
                )
            steps.append(self._step(i, prev, event, key, log, fails))
        return steps

    def _step(self, i: int, prev: Key, event: Event, key: Key, log, fails: tuple[int, ...] = ()) -> Step:  # type: ignore[no-untyped-def]
        failed = tuple(str(c) for c, ok in log.commands if isinstance(c, Start) and ok is False)
        cmds = tuple(f"{c}: {'ok' if ok else 'FAILED'}" if ok is not None else str(c).splitlines()[0] for c, ok in log.commands)
        return Step(i, event, failed, diff(prev, key, log), key, cmds, tuple(fails))


def describe_state(key: Key) -> tuple[str, ...]:
    out = [f"context {key.context or '(none)'}"]
    out.append("deployed: " + (", ".join(f"{g} on {p}" for g, p in key.deployments) or "nothing"))
    if key.failed:
        out.append("failed devices: " + ", ".join(key.failed))
    if key.down:
        out.append("platforms down: " + ", ".join(key.down))
    loads = [f"{p} {r}={a:g}" for p, items in key.loads for r, a in items]
    if loads:
        out.append("loads: " + ", ".join(loads))
    if key.standing:
        out.append("errors standing for: " + ", ".join(key.standing))
    return tuple(out)


def diff(prev: Key, key: Key, log) -> tuple[str, ...]:  # type: ignore[no-untyped-def]
    """What changed between two states, in repository terms."""
    out: list[str] = []
    if prev.context != key.context:
        out.append(f"IN_CONTEXT {prev.context} => {key.context}")
    for d in sorted(set(key.failed) - set(prev.failed)):
        out.append(f"-HAS_DEVICE {d}")
    for d in sorted(set(prev.failed) - set(key.failed)):
        out.append(f"+HAS_DEVICE {d}")
    for p in sorted(set(key.down) - set(prev.down)):
        out.append(f"{p} down")
    for p in sorted(set(prev.down) - set(key.down)):
        out.append(f"{p} up")
    if prev.loads != key.loads:
        before = {(p, r): a for p, items in prev.loads for r, a in items}
        after = {(p, r): a for p, items in key.loads for r, a in items}
        for p, r in sorted(set(before) | set(after)):
            a, b = before.get((p, r), 0), after.get((p, r), 0)
            if a != b:
                out.append(f"load {p} {r} {a:g} => {b:g}")
    for c, ok in log.commands:
        if isinstance(c, Start) and ok is False:
            out.append(f"start {c.graph} on {c.platform} FAILED")
    for g, p in sorted(set(prev.deployments) - set(key.deployments)):
        out.append(f"{g} -[DEPLOYED_ON => DEPLOYMENT_HISTORY]-> {p}")
    for g, p in sorted(set(key.deployments) - set(prev.deployments)):
        out.append(f"+{g} -[DEPLOYED_ON]-> {p}")
    for c, _ok in log.commands:
        if isinstance(c, RaiseError):
            out.append(f"error {c.kind}: {c.graph}" + (f" on {c.platform}" if c.platform else ""))
    if prev.standing != key.standing:
        out.append("standing errors: " + (", ".join(key.standing) or "none"))
    return tuple(out) or ("nothing",)
