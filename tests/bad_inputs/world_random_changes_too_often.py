# args: run {case}
# exit: 2
# expect: random changes every 1e-06 s on average over the horizon of 7200 s are about 7,200,000,000 changes, more than the 100,000 a run simulates; give mean_interval at least 0.072
"""A bad-input case: see tests/test_bad_inputs.py. Random requirement changes a microsecond apart (a run that
used to go on for hours without a word)."""
import dataclasses
from pathlib import Path

from desmon.loader import load_scenario
from desmon.sim.world import RandomChanges

_base = load_scenario(Path(__file__).resolve().parent.parent.parent / "scenarios" / "cloud_offload.py")
_every_microsecond = RandomChanges(changes=_base.world.random_changes.changes, mean_interval=1e-6)
scenario = dataclasses.replace(_base, world=dataclasses.replace(_base.world, random_changes=_every_microsecond))
