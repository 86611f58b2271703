"""The cyclic garbage collector while a simulation runs.

A run's heap is mostly long-lived (the model, the repository and its change log, the
trace records, the signal tables) and the run makes little cyclic garbage (finished
SimPy processes and their events), yet the collector's scans walk the long-lived part
again and again. :func:`collector_relaxed` freezes what exists out of the scans and
raises the young-generation threshold for the run; it restores both afterwards (a
caller's own frozen objects stay frozen) and collects the run's garbage, so that memory
stays flat over many runs in one process. No output depends on when the collector runs.

The collection after a run first runs while the caller's objects are still frozen, so it
scans only what the run made. The run's world becomes garbage only when the caller drops
it, later; it is collected by a full collection once what the runs left since the last
one reaches an eighth of the heap, so a process with a large heap (a sweep worker, a test
process) walks it once per many runs instead of after each. Both are measured in the
allocator's blocks (``sys.getallocatedblocks``: a walk of its pools, not of the objects):
the heap when the run froze it, and what the heap kept of the run after its collection.
The count lives on a :class:`Collector` the runs share: a caller that runs many
simulations in one process hands the same one to each (``desmon analyze --simulate``'s
runs, ``desmon estimate``'s serial runs and batches, the runs of a sweep's Dask worker);
a run given none counts alone.
20 runs of the coffee handover beside 6 million objects took 0.21 CPU s sharing a
Collector, 0.20 each with its own, where a full collection after each took 12.7 (60x;
``python -m bench.bench_sim --collector``, one run on the project's 2-core machine at
load 2 to 3).
"""

from __future__ import annotations

import contextlib
import gc
import sys
from typing import Iterator

__all__ = ["Collector", "collector_relaxed", "FULL_AFTER"]

#: a full collection once what the runs left reaches this fraction of the heap (allocated blocks)
FULL_AFTER = 1 / 8


class Collector:
    """The collector's bookkeeping of the runs that share this object: what they left
    behind since its last full collection (``left``, in the allocator's blocks), and the
    fraction of the heap at which a full collection runs (``full_after``). A caller running
    many simulations in one process hands them one (``SimWorld(collector=...)``); a run
    given none has its own. A run inside another of the same Collector (a world run within
    ``desmon estimate``'s run) neither freezes nor counts."""

    __slots__ = ("left", "full_after", "heap", "depth")

    def __init__(self, full_after: float = FULL_AFTER) -> None:
        self.left = 0
        self.full_after = full_after
        #: the heap (allocated blocks) when the current run froze it
        self.heap = 0
        #: how many of this Collector's relaxed runs enclose the code running now
        self.depth = 0

    @contextlib.contextmanager
    def relaxed(self, *, collect: bool = True) -> Iterator[None]:
        """Run with the objects built so far frozen out of the collector's scans (after a
        full collection first, if ``collect``) and its young-generation threshold raised;
        restored afterwards."""
        if self.depth:  # inside a run of this Collector: already frozen and raised
            self.depth += 1
            try:
                yield
            finally:
                self.depth -= 1
            return
        threshold = gc.get_threshold()
        # a caller that froze objects itself keeps them frozen: then nothing is frozen here
        # (an unfreeze would thaw the caller's objects too), only the threshold is raised.
        # With nothing frozen the count is at once: the walk is over an empty list
        freeze = gc.get_freeze_count() == 0
        if collect and freeze:
            gc.collect()
        if freeze:
            gc.freeze()
            self.heap = sys.getallocatedblocks()
        gc.set_threshold(100_000, 50, 100)
        self.depth = 1
        try:
            yield
        finally:
            self.depth = 0
            gc.set_threshold(*threshold)
            if freeze:
                self._collect_after_run()

    def _collect_after_run(self) -> None:
        """The run's own garbage now, with the caller's objects frozen out of the scan; then,
        thawed, a full collection once the runs' leftovers reach :attr:`full_after` of the
        heap (their cyclic garbage sits in the oldest generation, which the collector rarely
        scans: memory would grow run after run)."""
        gc.collect()
        self.left += max(0, sys.getallocatedblocks() - self.heap)  # what the run made and kept
        gc.unfreeze()
        if self.left >= self.full_after * self.heap:
            gc.collect()
            self.left = 0


def collector_relaxed(collector: Collector | None = None, *, collect: bool = True) -> "contextlib.AbstractContextManager[None]":
    """:meth:`Collector.relaxed` of ``collector`` (None: a new one, for this run alone)."""
    return (collector if collector is not None else Collector()).relaxed(collect=collect)
