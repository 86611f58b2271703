"""Many simulations in one process (``desmon analyze --simulate N``, sweeps, the agreement
tests) keep memory flat: the runs' garbage is collected once it reaches an eighth of the heap
(both counted in the allocator's blocks, desmon.sim.collector)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: sixty short runs in a fresh interpreter (a test process's own heap is so large that their
#: garbage stays under an eighth of it: there the collector rightly waits), printing the
#: heap before them and what they left; ``sys.argv[1]``, the fraction of the heap at which
#: the runs' Collector collects (a huge one: never)
RUNS = """
import gc, sys
import desmon.sim.collector as collector
from desmon.analyze.agreement import simulated_exposure
from desmon.loader import load_scenario

collector.Collector.__init__.__defaults__ = (float(sys.argv[1]),)
sc = load_scenario("scenarios/coffee_shift.py", {"hours": "0.25"})
simulated_exposure(sc, "desmon", range(3), 900.0)  # caches and imports settle
gc.collect()
before = sys.getallocatedblocks()
simulated_exposure(sc, "desmon", range(3, 63), 900.0)
print(before, sys.getallocatedblocks() - before)
"""


def _left(full_after: str) -> tuple[int, int]:
    proc = subprocess.run([sys.executable, "-c", RUNS, full_after], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    before, left = map(int, proc.stdout.split())
    return before, left


def test_objects_do_not_pile_up_run_after_run():
    # collected once the leftovers counted after each run reach an eighth of the heap, what
    # stays is at most about that share (a run's world becomes garbage after that count:
    # about twice what it left then) and the caches keyed by the run
    before, left = _left("0.125")
    assert left < before / 4, (before, left)
    # uncollected, each of these short runs leaves about 3,500 blocks of cyclic garbage
    # behind: the same bound fails
    before, never = _left("1e9")
    assert never >= before / 4, (before, never)
