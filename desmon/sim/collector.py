"""The cyclic garbage collector while a simulation runs.

A run's heap is mostly long-lived (the model, the repository and its change log, the
trace records, the signal tables) and the run makes little cyclic garbage (finished
SimPy processes and their events), yet the collector's scans walk the long-lived part
again and again. :func:`collector_relaxed` freezes what exists out of the scans and
raises the young-generation threshold for the run; it restores both afterwards (a
caller's own frozen objects stay frozen) and collects the run's garbage, so that memory
stays flat over many runs in one process. No output depends on when the collector runs.
"""

from __future__ import annotations

import contextlib
import gc
from typing import Iterator

__all__ = ["collector_relaxed"]


@contextlib.contextmanager
def collector_relaxed(*, collect: bool = True) -> Iterator[None]:
    """Run with the objects built so far frozen out of the collector's scans (after a
    full collection first, if ``collect``) and its young-generation threshold raised;
    restored afterwards."""
    threshold = gc.get_threshold()
    # a caller that froze objects itself keeps them frozen: then nothing is frozen here
    # (an unfreeze would thaw the caller's objects too), only the threshold is raised
    freeze = gc.get_freeze_count() == 0
    if collect and freeze:
        gc.collect()
    if freeze:
        gc.freeze()
    gc.set_threshold(100_000, 50, 100)
    try:
        yield
    finally:
        gc.set_threshold(*threshold)
        if freeze:
            gc.unfreeze()
            # the run's cyclic garbage now sits in the oldest generation, which the
            # collector rarely scans: collect it now, or memory grows run after run
            gc.collect()
