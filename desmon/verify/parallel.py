"""Expanding BFS levels in forked worker processes (``desmon verify --workers N``).

The search stays level-synchronous and its bookkeeping stays in the parent: the parent
cuts a level's frontier into chunks in BFS order, the workers run
:meth:`~desmon.verify.system.TransitionSystem.expand` on them (the same code, the same real
deployment core, inherited through ``fork`` with its memos warm), and the parent
consumes the records chunk by chunk *in frontier order*, exactly as it consumes its
own expansions. Which state is new, its parent, its label, every counter and every
counterexample are therefore the same for any number of workers.

Each worker remembers the keys it has already sent or been given (a bounded set,
cleared when it outgrows :data:`WORKER_MEMORY`) and sends those back as ``None``
instead of the key. That is sound because the parent has consumed everything the
worker sent before (a worker takes its chunks in increasing order and the parent
consumes them in that order), so such a key is in the parent's index already; and it
keeps the traffic to roughly the new states, since most transitions lead to states
seen before.
"""

from __future__ import annotations

import contextlib
import gc
import multiprocessing
import resource
import signal
from collections import deque
from concurrent.futures import Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from typing import TYPE_CHECKING, Callable, Iterator

from desmon.deployment.guard import ReactionStopped
from desmon.errors import CheckerError

if TYPE_CHECKING:  # pragma: no cover
    from desmon.verify.search import Segment
    from desmon.verify.state import Key
    from desmon.verify.system import TransitionSystem

__all__ = ["ExpansionPool", "WORKER_MEMORY"]

#: How often (seconds) the parent looks at the budget while it waits on a worker.
WAIT_LOOK = 0.2

#: States per chunk at most, and chunks in flight per worker.
CHUNK = 64
IN_FLIGHT = 3

#: Keys a worker remembers before it forgets them all (memory bound per worker).
WORKER_MEMORY = 200_000

class _Worker:
    """One worker process's own state: its system (inherited through ``fork``) and the
    keys it knows are in the parent's index (bounded by :data:`WORKER_MEMORY`)."""

    __slots__ = ("system", "known")

    def __init__(self, system: "TransitionSystem") -> None:
        self.system = system
        self.known: set = set()

    def expand(self, chunk: "list[Key]") -> "tuple[list[list[list[Segment]]], float]":
        """The expansions of ``chunk``'s states, and this worker's peak resident size (MB)."""
        checker, known = self.system, self.known
        if len(known) > WORKER_MEMORY:
            known.clear()
        known.update(chunk)  # the states being expanded are in the parent's index
        out = []
        for key in chunk:
            per_event = checker.expand(key, known)
            for segments in per_event:
                for i, (n, moved, names, rec) in enumerate(segments):
                    if rec is not None and rec[1] is not None:
                        known.add(rec[1])
                        # a plain tuple unpickles about 10x faster than a NamedTuple, and
                        # equals and hashes like the Key (the parent re-creates the Key)
                        segments[i] = (n, moved, names, (rec[0], tuple(rec[1]), *rec[2:]))
            out.append(per_event)
        return out, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


#: The one slot of a worker process: its :class:`_Worker`, set by :func:`_start_worker`
#: as the process starts (a pool's task is a module-level function, so the process's
#: object must be found through its module). Never set in the parent.
_WORKER: list[_Worker] = []


def _start_worker(checker: "TransitionSystem") -> None:
    """Worker initializer: the checker arrives through fork (never pickled); the parent
    pauses its cyclic collector for the search, and so does the worker. Ctrl-C reaches
    every process of the terminal's group: a worker ignores it (no traceback of its own)
    and finishes its chunk; the parent stops the search and reports it."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _WORKER[:] = [_Worker(checker)]
    gc.disable()


def _expand_chunk(chunk: "list[Key]") -> "tuple[list[list[list[Segment]]], float]":
    """The expansions of ``chunk``'s states by this process's worker (see :class:`_Worker`)."""
    if not _WORKER:  # pragma: no cover - a worker not started by ExpansionPool
        raise CheckerError("internal error: a checker worker started without its checker")
    return _WORKER[0].expand(chunk)


class ExpansionPool:
    """``workers`` forked processes expanding chunks of a BFS level in order.

    A worker that dies (killed, out of memory) or cannot be started ends the search
    with a one-line :class:`~desmon.errors.CheckerError` instead of a hang.
    """

    def __init__(self, checker: "TransitionSystem", workers: int) -> None:
        try:
            ctx = multiprocessing.get_context("fork")
        except ValueError:
            raise CheckerError(
                "--workers needs the 'fork' start method, which this platform lacks: run with --workers 1"
            ) from None
        self.workers = workers
        self.levels = 0  # BFS levels handed to the workers
        self.peak_mb = 0.0  # the largest worker's peak resident size
        self._pool = ProcessPoolExecutor(workers, mp_context=ctx, initializer=_start_worker, initargs=(checker,))
        #: why the search must stop now, or "" (the search's budget): asked while waiting on a
        #: worker, so that a worker stuck in a deployer's reaction cannot hold the search
        self.should_stop: Callable[[], str] = lambda: ""
        self._abandoned = False

    def expand(self, frontier: "list[Key]") -> Iterator["list[list[Segment]]"]:
        """The expansions of ``frontier``'s states, in frontier order.

        Chunks are submitted as the parent consumes them, at most ``IN_FLIGHT`` per
        worker ahead, so a search that stops early (a violation, ``max_states``) wastes
        little speculative work.
        """
        self.levels += 1
        size = max(1, min(CHUNK, len(frontier) // (self.workers * IN_FLIGHT)))
        window: deque[Future] = deque()
        for i in range(0, len(frontier), size):
            window.append(self._submit(frontier[i : i + size]))
            if len(window) >= self.workers * IN_FLIGHT:
                yield from self._result(window.popleft())
        while window:
            yield from self._result(window.popleft())

    def pids(self) -> list[int]:
        """The worker processes' ids (their memory counts in the search's budget)."""
        return list(getattr(self._pool, "_processes", None) or ())

    def _submit(self, chunk: "list[Key]") -> Future:
        try:
            return self._pool.submit(_expand_chunk, chunk)
        except BrokenProcessPool:
            raise _died() from None
        except OSError as exc:  # fork failed: too many processes, not enough memory
            raise CheckerError(f"cannot start {self.workers} worker processes ({exc.strerror or exc}): use fewer --workers") from None

    def _result(self, future: Future) -> "list[list[list[Segment]]]":
        while True:
            try:
                out, peak = future.result(timeout=WAIT_LOOK)
                break
            except TimeoutError:  # the chunk is still running: is the budget spent meanwhile?
                why = self.should_stop()
                if why:
                    self._abandon()
                    raise ReactionStopped(why) from None
            except BrokenProcessPool:
                raise _died() from None
        if peak > self.peak_mb:
            self.peak_mb = peak
        return out

    def _abandon(self) -> None:
        """Stop the workers now, whatever they are on (the search stops, and a worker may
        be stuck in a deployer's reaction that never returns)."""
        self._abandoned = True
        for proc in list((getattr(self._pool, "_processes", None) or {}).values()):
            with contextlib.suppress(Exception):
                proc.terminate()

    def close(self) -> float:
        """Stop the workers (after the chunks they are on, unless abandoned); returns the
        largest worker's peak resident size in MB."""
        self._pool.shutdown(wait=not self._abandoned, cancel_futures=True)
        return self.peak_mb


def _died() -> CheckerError:
    return CheckerError(
        "a checker worker process died (killed, or out of memory?): the search is incomplete; "
        "run with fewer --workers or a lower --max-states"
    )
