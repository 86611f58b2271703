"""Expanding BFS levels in forked worker processes (``desmon verify --workers N``).

The search stays level-synchronous and its bookkeeping stays in the parent: the parent
cuts a level's frontier into chunks in BFS order, the workers run
:meth:`~desmon.verify.system.TransitionSystem.expand` on them (the same code, the same real
deployment core, inherited through ``fork`` with its memos warm), and the parent
consumes the records chunk by chunk *in frontier order*, exactly as it consumes its
own expansions. Which state is new, its parent, its label, every counter and every
counterexample are therefore the same for any number of workers.

Each worker process runs its own :class:`_Worker` (forked with it, never pickled): the
workers take the chunks from one pipe in the order the parent sent them, and each sends
its records back on a pipe of its own. A worker remembers the keys it has already sent
or been given (a bounded set, cleared when it outgrows :data:`WORKER_MEMORY`) and sends
those back as ``None`` instead of the key. That is sound because the parent has
consumed everything the worker sent before (a worker takes its chunks in increasing
order and the parent consumes them in that order), so such a key is in the parent's
index already; and it keeps the traffic to roughly the new states, since most
transitions lead to states seen before.
"""

from __future__ import annotations

import contextlib
import gc
import multiprocessing
import resource
import signal
import threading
import time
from multiprocessing.connection import Connection, wait
from typing import TYPE_CHECKING, Any, Callable, Iterator

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

    def serve(self, tasks: Connection, take: Any, results: Connection) -> None:
        """The worker process: expand the chunks read from ``tasks`` (``take`` held while
        reading) until told to stop (None), and send each one's number, records, peak
        resident size and error (or None) on ``results``. The parent pauses its cyclic
        collector for the search, and so does the worker. Ctrl-C reaches every process of
        the terminal's group: a worker ignores it (no traceback of its own) and finishes
        its chunk; the parent stops the search and reports it."""
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        gc.disable()
        while True:
            with take:
                try:
                    task = tasks.recv()
                except (EOFError, OSError):
                    return
            if task is None:
                return
            n, chunk = task
            try:
                reply = (n, *self.expand(chunk), None)
            except BaseException as exc:  # raised again in the parent, as the search's own expansion raises it
                reply = (n, None, 0.0, exc)
            try:
                results.send(reply)
            except (EOFError, OSError):  # the parent has gone
                return
            except Exception as exc:  # an error that does not pickle: its text
                results.send((n, None, 0.0, CheckerError(f"a checker worker failed: {type(exc).__name__}: {exc}")))


class _Records:
    """The parent's side of the workers' record pipes: a thread reads every record as it
    arrives (so no worker waits to hand one over while the parent consumes another) and
    keeps it until the parent takes it, by chunk number."""

    def __init__(self, pipes: "list[Connection]", procs: list[Any]) -> None:
        self._cond = threading.Condition()
        self._done: dict[int, tuple] = {}  # chunk number -> (records, peak MB, error)
        #: a worker ended (or its records could not be read) before it was told to stop
        self.broken = ""
        self.closing = False
        self._thread = threading.Thread(target=self._read, args=(list(pipes), procs), name="desmon-worker-records", daemon=True)
        self._thread.start()

    def _read(self, pipes: "list[Connection]", procs: list[Any]) -> None:
        ends = {p.sentinel: p for p in procs}
        while pipes:
            for r in wait([*pipes, *ends], None):
                if r in ends:  # a worker ended: its last records are read first, then the pipe ends
                    del ends[r]
                    continue
                try:
                    n, out, peak, error = r.recv()  # type: ignore[union-attr]
                except (EOFError, OSError):
                    pipes.remove(r)  # type: ignore[arg-type]
                    self._note("" if self.closing else "died")
                    continue
                except Exception as exc:  # records that do not unpickle
                    n, out, peak, error = -1, None, 0.0, CheckerError(f"a checker worker's records could not be read: {type(exc).__name__}: {exc}")
                with self._cond:
                    if n < 0:
                        self.broken = self.broken or str(error)
                    self._done[n] = (out, peak, error)
                    self._cond.notify_all()

    def _note(self, why: str) -> None:
        if why:
            with self._cond:
                self.broken = self.broken or why
                self._cond.notify_all()

    def take(self, n: int, timeout: float) -> tuple | None:
        """The records of chunk ``n`` (None: not within ``timeout`` seconds); a worker that
        has died ends the search."""
        deadline = time.monotonic() + timeout
        with self._cond:
            while n not in self._done and not self.broken:
                left = deadline - time.monotonic()
                if left <= 0 or not self._cond.wait(left):
                    break
            if n in self._done:
                return self._done.pop(n)
            if self.broken == "died":
                raise _died()
            if self.broken:
                raise CheckerError(self.broken)
            return None

    def drop_before(self, n: int) -> None:
        """Forget the records of chunks before ``n`` (those a stopped level left)."""
        with self._cond:
            for k in [k for k in self._done if k < n]:
                del self._done[k]

    def join(self, timeout: float | None = None) -> None:
        self._thread.join(timeout)


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
        #: why the search must stop now, or "" (the search's budget): asked while waiting on a
        #: worker, so that a worker stuck in a deployer's reaction cannot hold the search
        self.should_stop: Callable[[], str] = lambda: ""
        self._abandoned = False
        self._procs: list[Any] = []
        pipes: list[Connection] = []  # one per worker, its records
        self._sent = self._taken = 0  # chunks sent; the next chunk to consume
        tasks, self._tasks = ctx.Pipe(duplex=False)
        take = ctx.Lock()  # one worker reads the next chunk at a time
        try:
            for _ in range(workers):
                records, mine = ctx.Pipe(duplex=False)
                proc = ctx.Process(target=_Worker(checker).serve, args=(tasks, take, mine))
                pipes.append(records)
                proc.start()
                mine.close()
                self._procs.append(proc)
        except OSError as exc:  # fork failed: too many processes, not enough memory
            self._abandon()
            raise CheckerError(f"cannot start {workers} worker processes ({exc.strerror or exc}): use fewer --workers") from None
        finally:
            tasks.close()
        self._records = _Records(pipes, self._procs)

    def expand(self, frontier: "list[Key]") -> Iterator["list[list[Segment]]"]:
        """The expansions of ``frontier``'s states, in frontier order.

        Chunks are sent as the parent consumes them, at most ``IN_FLIGHT`` per worker
        ahead, so a search that stops early (a violation, ``max_states``) wastes little
        speculative work.
        """
        self.levels += 1
        size = max(1, min(CHUNK, len(frontier) // (self.workers * IN_FLIGHT)))
        starts = range(0, len(frontier), size)
        first, ahead = self._sent, self.workers * IN_FLIGHT
        self._records.drop_before(first)  # records of chunks a stopped level left
        for i in range(len(starts)):
            while self._sent - first < min(len(starts), i + ahead):
                k = starts[self._sent - first]
                self._send(frontier[k : k + size])
            yield from self._result(first + i)

    def pids(self) -> list[int]:
        """The worker processes' ids (their memory counts in the search's budget)."""
        return [p.pid for p in self._procs if p.pid is not None]

    def _send(self, chunk: "list[Key]") -> None:
        try:
            self._tasks.send((self._sent, chunk))
        except OSError:
            raise _died() from None
        self._sent += 1

    def _result(self, n: int) -> "list[list[list[Segment]]]":
        """The records of chunk ``n``, waiting for them."""
        while True:
            got = self._records.take(n, WAIT_LOOK)
            if got is not None:
                break
            why = self.should_stop()  # the chunk is still running: is the budget spent meanwhile?
            if why:
                self._abandon()
                raise ReactionStopped(why)
        out, peak, error = got
        self._taken = n + 1
        if error is not None:
            raise error
        if peak > self.peak_mb:
            self.peak_mb = peak
        return out

    def _abandon(self) -> None:
        """Stop the workers now, whatever they are on (the search stops, and a worker may
        be stuck in a deployer's reaction that never returns)."""
        self._abandoned = True
        for proc in self._procs:
            with contextlib.suppress(Exception):
                proc.terminate()

    def close(self) -> float:
        """Stop the workers (after the chunks they are on, unless abandoned: the chunks
        sent and not consumed are dropped); returns the largest worker's peak resident
        size in MB."""
        self._records.closing = True
        if not self._abandoned:
            if self._sent > self._taken:  # speculative chunks of a search that stopped early
                self._abandon()
            else:
                for _ in self._procs:
                    with contextlib.suppress(OSError):
                        self._tasks.send(None)
        for proc in self._procs:
            proc.join(None if not self._abandoned else 5.0)
            if proc.is_alive():  # pragma: no cover - a worker that ignores SIGTERM
                proc.kill()
                proc.join()
        self._records.join(5.0)
        self._tasks.close()
        return self.peak_mb


def _died() -> CheckerError:
    return CheckerError(
        "a checker worker process died (killed, or out of memory?): the search is incomplete; "
        "run with fewer --workers or a lower --max-states"
    )
