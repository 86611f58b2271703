"""Expanding BFS levels in forked worker processes (``desmon verify --workers N``).

The search stays level-synchronous and its bookkeeping stays in the parent: the parent
cuts a level's frontier into chunks in BFS order, the workers run
:meth:`~desmon.verify.checker.Checker.expand` on them (the same code, the same real
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

import gc
import multiprocessing
import resource
from collections import deque
from typing import TYPE_CHECKING, Iterator

from desmon.errors import CheckerError

if TYPE_CHECKING:  # pragma: no cover
    from desmon.verify.checker import Checker, Segment
    from desmon.verify.state import Key

__all__ = ["ExpansionPool", "WORKER_MEMORY"]

#: States per chunk at most, and chunks in flight per worker.
CHUNK = 64
IN_FLIGHT = 3

#: Keys a worker remembers before it forgets them all (memory bound per worker).
WORKER_MEMORY = 200_000

_checker: "Checker | None" = None  # the worker's checker, inherited through fork
_known: set = set()


def _expand_chunk(chunk: "list[Key]") -> "list[list[list[Segment]]]":
    checker = _checker
    assert checker is not None, "worker started without a checker"
    known = _known
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
    return out


class ExpansionPool:
    """``workers`` forked processes expanding chunks of a BFS level in order."""

    def __init__(self, checker: "Checker", workers: int) -> None:
        global _checker
        try:
            ctx = multiprocessing.get_context("fork")
        except ValueError:
            raise CheckerError(
                "--workers needs the 'fork' start method, which this platform lacks: run with --workers 1"
            ) from None
        self.workers = workers
        _checker = checker  # inherited by the forked workers; never used in the parent
        try:
            # the parent pauses its cyclic collector for the search; so do the workers
            self._pool = ctx.Pool(workers, initializer=gc.disable)
        finally:
            _checker = None

    def expand(self, frontier: "list[Key]") -> Iterator["list[list[Segment]]"]:
        """The expansions of ``frontier``'s states, in frontier order.

        Chunks are submitted as the parent consumes them, at most ``IN_FLIGHT`` per
        worker ahead, so a search that stops early (a violation, ``max_states``) wastes
        little speculative work.
        """
        size = max(1, min(CHUNK, len(frontier) // (self.workers * IN_FLIGHT)))
        chunks = (frontier[i : i + size] for i in range(0, len(frontier), size))
        window: deque = deque()
        for chunk in chunks:
            window.append(self._pool.apply_async(_expand_chunk, (chunk,)))
            if len(window) >= self.workers * IN_FLIGHT:
                yield from window.popleft().get()
        while window:
            yield from window.popleft().get()

    def close(self) -> float:
        """Stop the workers; returns the largest peak resident size (MB) of any child
        process this process has waited for, the workers included."""
        self._pool.terminate()
        self._pool.join()
        return resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0
