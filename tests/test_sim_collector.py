"""A simulation run relaxes the cyclic garbage collector and gives it back as it found it."""

from __future__ import annotations

import gc
from pathlib import Path

from desmon.loader import load_scenario
from desmon.sim.collector import collector_relaxed
from desmon.sim.engine import SimWorld

ROOT = Path(__file__).resolve().parents[1]


def test_a_run_gives_the_collector_back_as_it_found_it() -> None:
    before = gc.get_threshold()
    frozen = gc.get_freeze_count()
    seen = []
    world = SimWorld(load_scenario(ROOT / "scenarios" / "platform_crash.py"), seed=0, until=120.0)
    step = world.env.step

    def watched() -> None:
        seen.append((gc.get_threshold(), gc.get_freeze_count()))
        step()

    world.env.step = watched  # type: ignore[method-assign]
    world.run()
    assert seen and seen[0][0] != before and seen[0][1] > frozen  # relaxed while the run steps
    assert gc.get_threshold() == before
    assert gc.get_freeze_count() == frozen


def test_a_callers_own_frozen_objects_stay_frozen() -> None:
    gc.freeze()
    try:
        mine = gc.get_freeze_count()
        with collector_relaxed():
            assert gc.get_freeze_count() == mine
        assert gc.get_freeze_count() == mine  # not thawed by the run
    finally:
        gc.unfreeze()
