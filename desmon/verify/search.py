"""Search core: what every checker engine shares.

An engine (:mod:`~desmon.verify.direct`, :mod:`~desmon.verify.table`) explores the
transition system of :mod:`desmon.verify.system` breadth-first; this module holds what
a search is measured by and ends with, whichever engine runs it:

* the result (:class:`CheckResult`, the verdicts, :func:`finish`);
* the budgets and limits (:class:`Budget`: the time limit, the memory budget, Ctrl-C,
  and the progress line it rewrites) and the search's surroundings (:func:`ctrl_c`,
  :func:`paused_gc`);
* the search tree (:class:`Trail`: parent pointers and transition labels of the
  states, counterexamples rebuilt by replaying their labels through the real
  deployment core, and when the search has found what it looks for);
* the level-by-level loop both engines run (:class:`BreadthFirst`), and a level kept as a
  range of state numbers (:class:`Queue`);
* what a transition reports to a search loop (:data:`Record`, :data:`Segment`).

State keys are :class:`desmon.verify.state.Key`; counterexample steps are in
:mod:`desmon.verify.trace`.
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
from typing import TYPE_CHECKING, Any, Callable, Container, Iterable, Iterator, Protocol, Sequence, TextIO

from desmon.deployment.guard import CRASH, EXIT_CRASHED, ReactionStopped
from desmon.progress import StatusLine
from desmon.verify.state import Key
from desmon.verify.trace import Counterexample, Label, Step

if TYPE_CHECKING:  # pragma: no cover
    from desmon.deployment.invariants import Invariant

__all__ = [
    "Exploration",
    "HOLDS", "VIOLATED", "INCOMPLETE", "CRASHED", "EXIT_CRASHED", "INTERRUPTED", "EXIT_INTERRUPTED", "NOT_CHECKED", "Record", "Segment",
    "CheckResult", "Budget", "Replayable", "Trail", "Queue", "BreadthFirst", "finish", "final_status", "ctrl_c", "paused_gc", "resident_mb", "proportional_mb", "peak_mb",
    "MEMORY_EVERY", "MEMORY_EVERY_WORKERS",
]

HOLDS, VIOLATED, INCOMPLETE = "HOLDS", "VIOLATED", "INCOMPLETE"
#: the deployer failed (raised, yielded a wrong command, never ended) in a reachable
#: state: the counterexample is the shortest path to that reaction (exit 4)
CRASHED = "CRASHED"
#: why a search stopped by Ctrl-C is incomplete (:attr:`CheckResult.incomplete`), and its exit
#: code (128 + SIGINT, as a shell reports it)
INTERRUPTED, EXIT_INTERRUPTED = "interrupted", 130

#: Invariants the checker cannot evaluate, and where they are checked instead. Its states
#: keep no infrastructure running list, stop count or DEPLOYMENT_HISTORY edges (the
#: SystemView it builds leaves ``running`` / ``stops`` / ``history`` None), so ``history``
#: could never fail here: it is left out of the checked set and refused by name.
NOT_CHECKED = {"history": "sim audit and fuzz only"}

#: One transition as :meth:`TransitionSystem.expand <desmon.verify.system.TransitionSystem.expand>`
#: reports it to the search loop: (failed start indices, the successor's canonical key or
#: None if already known, whether the state moved, the reaction's branch names, an
#: invariants its reaction broke and repaired before quiescence (invariant, message, after
#: what; an instantaneous one after a start, or the reaction as a whole), the invariants a new
#: successor violates).
Record = tuple[tuple[int, ...], "Key | None", bool, tuple[str, ...], tuple[tuple[str, str, str], ...], tuple[tuple[str, str], ...]]

#: A run of routine transitions (only counted: how many, how many moved the state, their
#: branch names) followed by one :data:`Record`, or by None at the end of an event.
Segment = tuple[int, int, tuple[str, ...], "Record | None"]



@dataclass
class Exploration:
    """What an engine's search found: counterexamples by invariant, why it stopped early
    ("" if it did not), its depth, and the distinct states in BFS order."""

    found: dict[str, Counterexample]
    incomplete: str
    depth: int
    explored: Sequence[Key]


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
    #: the process's resident memory when the search began (MB; see :attr:`bytes_per_state`)
    start_mb: float = field(default=0.0, compare=False)
    counterexamples: list[Counterexample] = field(default_factory=list)
    enabled: Counter = field(default_factory=Counter)
    new_states: Counter = field(default_factory=Counter)
    changed: Counter = field(default_factory=Counter)
    rules: Counter = field(default_factory=Counter)
    branches: Counter = field(default_factory=Counter)
    symmetry: bool = False
    #: under ``symmetry``: the states the explored orbits hold (their sizes summed:
    #: :meth:`Symmetry.states_covered <desmon.verify.symmetry.Symmetry.states_covered>`)
    states_covered: int | None = None
    not_checked: tuple[str, ...] = ()  # invariants left to the sim audit and the fuzzer (NOT_CHECKED)
    #: what the model leaves out of the scenario's World that can change the verdict
    #: (:func:`desmon.verify.bounds.unmodelled`), one line each
    unmodelled: tuple[str, ...] = ()
    workers: int = 1
    peak_workers_mb: float = 0.0  # the largest worker process's peak resident size (workers > 1)
    worker_levels: int = 0  # BFS levels the workers expanded (levels under PARALLEL_LEVEL states stay in-process)
    engine: str = "direct"  # "table" or "direct" (see Checker.run)
    records: int = 0  # table engine: real runs of the core it recorded (reactions and invariant checks)
    engine_note: str = ""  # why engine "auto" ran the direct engine
    incomplete: str = ""  # why the search stopped early ("" if it did not), whatever the verdict
    timeout: float | None = None  # the time limit it ran under (seconds)
    max_memory: float | None = None  # the memory budget it ran under (MB)
    #: the distinct (canonical) states the search explored, in BFS order (not part of the report)
    explored: Sequence["Key"] = field(default=(), repr=False, compare=False)

    @property
    def states_per_second(self) -> float:
        return self.states / self.seconds if self.seconds > 0 else float("inf")

    @property
    def bytes_per_state(self) -> float:
        """The resident memory the search added, per state: (peak resident size - resident
        size at its start) / states (the peak is the process's: a search after a larger
        one in the same process reads low)."""
        return max(self.peak_mb - self.start_mb, 0.0) * 2**20 / self.states if self.states else 0.0

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
        return {HOLDS: 0, VIOLATED: 1, INCOMPLETE: 3, CRASHED: EXIT_CRASHED}[self.verdict]


def peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def resume_gc() -> None:
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
        self.interrupted = False  # set by the Ctrl-C handler of ctrl_c
        self.memory = 0.0  # the last resident memory read (MB; the workers' shares included)
        #: the worker processes whose memory counts (set by the direct engine's pool)
        self.pids: Callable[[], Iterable[int]] = tuple
        #: other processes whose memory counts: a user's deployer's worker (:mod:`desmon.verify.isolation`)
        self.others: Callable[[], Iterable[int]] = tuple
        #: (states, transitions, depth) of the search so far, for the progress line
        self.status: Callable[[], tuple[int, int, int]] = lambda: (0, 0, 0)
        #: the sizes of the BFS levels explored so far (the growth the progress line and a
        #: spent memory budget report), and the resident memory when the search began (MB)
        self.levels: Callable[[], Sequence[int]] = tuple
        self.start_mb = 0.0
        self._next_look = t0
        self._last_progress = -math.inf
        self._line = StatusLine(self.out)

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

    def urgent(self) -> str:
        """:meth:`spent` without the progress line: the time, the memory and Ctrl-C, for the
        timer that interrupts a deployer's code that runs on without yielding
        (:func:`desmon.deployment.guard.watching`); it sets :attr:`reason` as spent does."""
        if not self.reason:
            if self.interrupted:
                self.reason = INTERRUPTED
            elif time.perf_counter() > self.deadline:
                self.reason = f"timeout {self.timeout:g}s"
            elif self.max_memory is not None:
                mb = self.measure([*self.pids(), *self.others()])
                if mb > self.max_memory:
                    self.memory = mb
                    self.reason = f"memory budget {self.max_memory:g} MB reached: {mb:,.0f} MB resident"
        return self.reason

    def _look(self, now: float) -> None:
        pids = [*self.pids(), *self.others()]
        self._next_look = now + (MEMORY_EVERY_WORKERS if pids else MEMORY_EVERY)
        if self.max_memory is not None or self.progress:
            self.memory = self.measure(pids)
        if self.max_memory is not None and self.memory > self.max_memory:
            self.reason = f"memory budget {self.max_memory:g} MB reached: {self.memory:,.0f} MB resident" + self.growth()
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
        return peak_mb() if mb is None else mb

    def show(self, now: float) -> None:
        """Rewrite the progress line: states, states/s, depth, transitions, memory and time, with their budgets."""
        states, transitions, depth = self.status()
        elapsed = now - self.t0
        rate = states / elapsed if elapsed > 0 else 0.0
        memory = f"{self.memory:,.0f} MB" + (f" of {self.max_memory:g}" if self.max_memory is not None else "")
        clock = f"{elapsed + self.before:,.0f}s" + (f" of {self.timeout:g}s" if self.timeout is not None else "")
        per_state = f"  {(self.memory - self.start_mb) * 2**20 / states:,.0f} B/state" if states and self.memory else ""
        line = f"  {states:,} states  {rate:,.0f} states/s  depth {depth}  {transitions:,} transitions  memory {memory}{per_state}  time {clock}"
        self._line.show(line + self.growth())

    def growth(self) -> str:
        """How the BFS levels were still growing ("" before two levels): the last one's size
        over the one before, and the next two levels' sizes if they keep that rate."""
        sizes = self.levels()
        if len(sizes) < 2 or not sizes[-2]:
            return ""
        rate = sizes[-1] / sizes[-2]
        return f"; levels growing {rate:.2f}x: about {sizes[-1] * rate:,.0f} and {sizes[-1] * rate * rate:,.0f} states next"

    def close(self) -> None:
        """End the progress line (if one was shown) before the report."""
        self._line.close()


@contextlib.contextmanager
def ctrl_c(budget: Budget) -> Iterator[None]:
    """While a search runs, a first Ctrl-C asks it to stop at its next check (and report
    what it explored); a second one interrupts at once (``KeyboardInterrupt``, which the
    engines also turn into an interrupted result). Only in the main thread, and only
    where Python's own handler is installed, or the guard's count of it (the reaction
    limit's: :meth:`~desmon.deployment.guard.Guard.deadline`), which it restores after;
    a program's own handler is left alone."""
    previous = signal.getsignal(signal.SIGINT)
    python_own = previous is signal.default_int_handler or getattr(previous, "python_own", False)
    if threading.current_thread() is not threading.main_thread() or not python_own:
        yield
        return

    def stop(signum: int, frame: Any) -> None:
        budget.interrupted = True
        signal.signal(signal.SIGINT, previous)

    signal.signal(signal.SIGINT, stop)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


@contextlib.contextmanager
def paused_gc() -> Iterator[None]:
    """The cyclic collector paused while a search runs (a search makes no reference cycles,
    ``tests/test_verify.py`` checks it, but the collector would still walk the millions
    of keys it holds again and again: a third of the time at 80,000 states), and resumed
    cheaply after it (:func:`resume_gc`)."""
    collecting = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if collecting:
            resume_gc()


class Replayable(Protocol):
    """What a search's bookkeeping needs of the system it explores
    (:class:`~desmon.verify.system.TransitionSystem` is the one): the invariants it
    checks, and the replay of a path's labels through the real core."""

    @property
    def invariants(self) -> tuple[Invariant, ...]: ...

    def replay(self, labels: list[Label], expect: list[Key] | None = None, initial: tuple[int, ...] = ()) -> list[Step]: ...

    def concrete(self, name: str, msg: str, during: str | None) -> tuple[str, str | None]: ...


class Trail:
    """The search tree of a BFS: each state's parent and transition label, by state number,
    and the counterexamples found so far, each rebuilt (once per invariant) by replaying
    the labels on its path from the initial state through the real core, which also
    checks that the replay lands on the stored states (determinism).

    ``key_of(i)`` gives the key of state number ``i`` (the engines store states their
    own way). A label is interned once: ``label_id(lookup, label)`` numbers ``label``
    under the engine's ``lookup`` key for it.
    """

    def __init__(self, system: Replayable, key_of: Callable[[int], Key], keep_going: bool, label_of: Callable[[int], Label] | None = None) -> None:
        self.system = system
        self.key_of = key_of
        self.keep_going = keep_going
        self.parent = array("i", [-1])  # (4 bytes a state: at most 2**31 states)
        #: the initial states, numbered first: the failed start indices of each one's first reaction
        self.roots: list[tuple[int, ...]] = [()]
        #: with ``label_of`` (the label of the transition from state i's parent to i, found
        #: again when a path is rebuilt) no label is stored: a state costs its parent only
        self.label_of = label_of
        self.label = array("i", [-1] if label_of is None else [])
        self.labels: list[Label] = []
        self._label_ids: dict[Any, int] = {}
        self.found: dict[str, Counterexample] = {}
        self.wanted = {i.name for i in system.invariants}

    def set_roots(self, fails: list[tuple[int, ...]]) -> None:
        """The initial states are numbered 0 to ``len(fails) - 1``; each one's first reaction failed the starts at its ``fails``."""
        self.roots = list(fails)
        self.parent = array("i", [-1] * len(fails))
        if self.label_of is None:
            self.label = array("i", [-1] * len(fails))

    def label_id(self, lookup: Any, label: Label) -> int:
        li = self._label_ids.get(lookup)
        if li is None:
            li = self._label_ids[lookup] = len(self.labels)
            self.labels.append(label)
        return li

    def add(self, parent: int, lookup: Any, label: Label) -> None:
        """The next state's parent and label."""
        self.parent.append(parent)
        if self.label_of is None:
            self.label.append(self.label_id(lookup, label))

    def extend(self, parents: Any, label_ids: Any) -> None:
        """The next states' parents and label numbers (numpy arrays of :meth:`label_id`)."""
        self.parent.frombytes(parents.astype("int32").tobytes())
        if self.label_of is None:
            self.label.frombytes(label_ids.astype("int32").tobytes())

    def path(self, i: int) -> tuple[list[Label], list[Key], tuple[int, ...]]:
        """The labels from an initial state to state ``i``, the states on the way, and the
        starts that initial state's first reaction failed."""
        ls: list[Label] = []
        ks: list[Key] = []
        parent, key_of = self.parent, self.key_of
        label_of = self.label_of or (lambda j: self.labels[self.label[j]])
        while parent[i] >= 0:
            ks.append(key_of(i))
            ls.append(label_of(i))
            i = parent[i]
        ks.append(key_of(i))
        ls.reverse()
        ks.reverse()
        return ls, ks, self.roots[i]

    def record(
        self, name: str, msg: str, i: int, during: str | None = None, extra: Label | None = None, initial: tuple[int, ...] | None = None,
    ) -> None:
        """A violation of ``name`` in state ``i`` (or, with ``extra``, during the transition
        ``extra`` out of it; with ``initial``, during the first reaction that failed those
        starts and reached the initial state ``i``): its counterexample, unless the invariant
        has one already."""
        if name in self.found:
            return
        ls, ks, root = self.path(i)
        initial = root if initial is None else initial
        if extra is not None:
            ls.append(extra)
        steps = tuple(self.system.replay(ls, expect=ks, initial=initial))
        msg, during = self.system.concrete(name, msg, during)  # (found on a stored state: said of the trace's own)
        self.found[name] = Counterexample(name, msg, steps, during)

    def done(self) -> bool:
        """Whether the search has what it looks for: a counterexample (or one of each
        invariant with ``keep_going``)."""
        return (not self.keep_going and bool(self.found)) or self.wanted <= set(self.found) or CRASH in self.found

    def truncate(self, states: list | array) -> None:  # type: ignore[type-arg]
        """Drop a state half-added when a second Ctrl-C came (``states``: the engine's list of them)."""
        n = min(len(states), len(self.parent), len(self.label) if self.label_of is None else len(self.parent))
        del states[n:], self.parent[n:], self.label[n:]


class Queue:
    """The next level of a BFS that numbers its states in order: the range of numbers it
    queues, and those in that range it skipped (a state that violates an invariant, where
    the search stops at the first); no array of state numbers is kept (the table engine's
    frontier)."""

    def __init__(self, first: int) -> None:
        self.first = self.end = first
        self.skipped: list[int] = []

    def extend(self, lo: int, hi: int) -> None:
        """Queue the states numbered ``lo`` to ``hi`` (excluded), the next ones numbered."""
        self.skipped.extend(range(self.end, lo))
        self.end = hi

    def append(self, i: int) -> None:
        self.extend(i, i + 1)

    def states(self) -> Sequence[int]:
        """The queued state numbers, ascending."""
        if not self.skipped:
            return range(self.first, self.end)
        import numpy as np  # (only an engine with arrays keeps a Queue: the CLI loads no numpy)

        return np.setdiff1d(np.arange(self.first, self.end, dtype=np.int64), np.array(self.skipped, dtype=np.int64))


class BreadthFirst:
    """The search loop of both engines: BFS level by level from state 0 until the search
    has what it looks for, hits a cap or its budget, or Ctrl-C. An engine sets ``trail``,
    ``budget``, ``res``, ``max_states`` and ``max_depth``, and expands a level in
    :meth:`_level`."""

    trail: Trail
    budget: Budget
    res: CheckResult
    max_states: int | None
    max_depth: int | None

    def _level(self, frontier: Any) -> Any:
        """Expand the states numbered in ``frontier``; returns the next level's numbers."""
        raise NotImplementedError

    def _search(self, states: list | array, violations: list[list[tuple[Any, ...]]]) -> tuple[dict[str, Counterexample], str, int]:  # type: ignore[type-arg]
        """The BFS from the initial states, numbered 0 to ``len(violations) - 1`` (the trail's
        roots), whose invariant ``violations`` are given, each initial state's; ``states`` is
        the engine's list of them (their count, and what a second Ctrl-C truncates). Returns
        (counterexamples found, why incomplete or "", depth), and counts the states and
        transitions into ``res``."""
        trail, budget = self.trail, self.budget
        self.depth = self.transitions = 0
        self.incomplete = ""
        budget.status = lambda: (len(states), self.transitions, self.depth)
        sizes: list[int] = [len(violations)]
        budget.levels = lambda: sizes
        frontier: Any = []
        for root, bad in enumerate(violations):
            for name, msg, *where in bad:  # (the initial reaction's own findings say where in it, and another choice's which)
                trail.record(name, msg, root, where[0] if where else None, initial=where[1] if len(where) > 1 else None)
            if not bad or trail.keep_going:  # (as any state that violates an invariant: :meth:`_add_state`)
                frontier.append(root)
        self.any_found = bool(trail.found)
        try:
            while len(frontier) and not self._finished() and not self.incomplete:
                if self.max_depth is not None and self.depth >= self.max_depth:
                    self.incomplete = f"max depth {self.max_depth} reached with {len(frontier)} states unexplored"
                    break
                frontier = self._level(frontier)
                if len(frontier):
                    self.depth += 1
                    sizes.append(len(frontier))
        except KeyboardInterrupt:  # a second Ctrl-C (or one the handler could not catch)
            self.incomplete = INTERRUPTED
            trail.truncate(states)
        except ReactionStopped as stop:  # the budget ran out inside a deployer's reaction
            self.incomplete = budget.reason or str(stop)
            trail.truncate(states)
        # the status closure points back at this search: let it go (no reference cycle is left behind)
        budget.status = final_status(len(states), self.transitions, self.depth)
        self.res.states, self.res.transitions = len(states), self.transitions
        return trail.found, self.incomplete, self.depth

    def _finished(self) -> bool:
        return self.any_found and self.trail.done()

    def _add_state(self, ni: int, parent: int, lookup: Any, label: Label, kind: str, bad: Iterable[tuple[str, str]], nxt: Any) -> None:
        """State number ``ni`` is new, reached from ``parent`` by ``label`` (numbered under
        ``lookup``: :meth:`Trail.label_id`) and counted under its event's ``kind``, and
        queued in ``nxt``; one that violates invariants (``bad``: (name, message) pairs) is
        recorded, and explored only by a search that collects every invariant's
        counterexample (``keep_going``): a shorter path to another invariant's violation
        may lead through it, and the BFS finds each one's shortest only if it goes on."""
        self.trail.add(parent, lookup, label)
        self.res.new_states[kind] += 1
        if self.max_states is not None and ni + 1 >= self.max_states:
            self.incomplete = f"max states {self.max_states:,} reached"
        if bad:
            for name, msg in bad:
                self.trail.record(name, msg, ni)
            self.any_found = True
            if not self.trail.keep_going:  # the search ends with this level: nothing beyond it is explored
                return
        nxt.append(ni)

    def _record_each(self, found: Iterable[tuple[str, str, str]], repaired: Container[str], state: int, label: Label) -> bool:
        """Record what the transition ``label`` out of ``state`` broke inside its reaction
        (``found``: invariant, message, after what) and repaired before quiescence (the
        invariants ``repaired``), each not found yet, in order; True (at once) if the
        search then has what it looks for."""
        trail = self.trail
        for name, msg, during in found:
            if name in repaired and name not in trail.found:
                trail.record(name, msg, state, during, label)
                self.any_found = True
                if trail.done():
                    return True
        return False


def final_status(states: int, transitions: int, depth: int) -> Callable[[], tuple[int, int, int]]:
    """A :attr:`Budget.status` that reports a finished search's figures (an engine's own
    status closure points back at the engine: replacing it leaves no reference cycle)."""
    figures = (states, transitions, depth)
    return lambda: figures


def finish(res: CheckResult, system: Replayable, found: dict[str, Counterexample], incomplete: str, depth: int, budget: Budget) -> CheckResult:
    """Verdict, depth, time and memory of a finished search (any engine)."""
    res.depth = max([depth] + [c.length for c in found.values()])
    res.seconds = time.perf_counter() - budget.t0
    res.peak_mb = peak_mb()
    res.incomplete = incomplete
    res.counterexamples = [found[i.name] for i in system.invariants if i.name in found]
    if CRASH in found:  # the deployer's fault ends the search: what it found before stays listed
        crash = found[CRASH]
        res.counterexamples.append(crash)
        res.verdict = CRASHED
        res.reason = f"the deployer failed in step {crash.length}"
    elif res.counterexamples:
        res.verdict = VIOLATED
        res.reason = ", ".join(c.invariant for c in res.counterexamples)
        if incomplete:
            res.reason += f" (search incomplete: {incomplete})"
    elif incomplete:
        res.verdict, res.reason = INCOMPLETE, incomplete
    return res
