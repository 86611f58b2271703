"""A simulation run relaxes the cyclic garbage collector and gives it back as it found it."""

from __future__ import annotations

import gc
import subprocess
import sys
from pathlib import Path

from desmon.loader import load_scenario
from desmon.sim.engine import SimWorld

ROOT = Path(__file__).resolve().parents[1]


def test_a_run_gives_the_collector_back_as_it_found_it() -> None:
    before = gc.get_threshold()
    frozen = gc.get_freeze_count()
    seen = []
    world = SimWorld(load_scenario(ROOT / "scenarios" / "platform_crash.py"), seed=0, until=120.0)
    step = world.env.step

    def watched() -> None:
        if not seen:  # (the first step: counting the frozen objects walks them all)
            seen.append((gc.get_threshold(), gc.get_freeze_count()))
        step()

    world.env.step = watched  # type: ignore[method-assign]
    world.run()
    assert seen and seen[0][0] != before and seen[0][1] > frozen  # relaxed while the run steps
    assert gc.get_threshold() == before
    assert gc.get_freeze_count() == frozen


#: run by a fresh interpreter: in the test process another thread (pytest-xdist's, which
#: talks to the controller) may free an object this thread froze, and lower the count
CALLERS_FROZEN = """
import gc
from desmon.sim.collector import collector_relaxed
gc.freeze()
mine = gc.get_freeze_count()
with collector_relaxed():
    assert gc.get_freeze_count() == mine, (gc.get_freeze_count(), mine)
assert gc.get_freeze_count() == mine, (gc.get_freeze_count(), mine)  # not thawed by the run
"""


def test_a_callers_own_frozen_objects_stay_frozen() -> None:
    proc = subprocess.run([sys.executable, "-c", CALLERS_FROZEN], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
