"""Many simulations in one process (``desmon analyze --simulate N``, sweeps, the agreement
tests) keep memory flat: the runs' garbage is collected once it reaches an eighth of the heap."""

from __future__ import annotations

import gc

from desmon.analyze.agreement import simulated_exposure
from desmon.loader import load_scenario


def test_objects_do_not_pile_up_run_after_run():
    sc = load_scenario("scenarios/coffee_shift.py", {"hours": "0.25"})
    simulated_exposure(sc, "desmon", range(3), 900.0)  # caches and imports settle
    gc.collect()
    before = len(gc.get_objects())
    simulated_exposure(sc, "desmon", range(3, 63), 900.0)
    after = len(gc.get_objects())
    # uncollected, each of these short runs leaves over a thousand objects of cyclic garbage behind (about 80,000 for
    # the sixty); collected once the leftovers reach an eighth of the heap (FULL_AFTER), what stays is at most that
    # share of the heap and the caches keyed by the run (about 140 a run)
    assert after - before < before / 8 + 60 * 250, (before, after)
