# args: analyze {case} --horizon 600
# exit: 2
# expect: World slips are scripted (a slip at 23 s)
# expect: give slip_rate=
"""A bad-input case: see tests/test_bad_inputs.py. The coffee shift with three scripted slips:
analyze counted no undetected slip (0.0000 per hour) where desmon run misses one of them,
and its "leaves out" list said nothing."""
import sys
from dataclasses import replace
from pathlib import Path

from desmon.sim.world import Slip

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "scenarios"))
from coffee_shift import scenario as shift  # noqa: E402

scenario = replace(shift, name="shift_with_scripted_slips", world=replace(shift.world, slips=(Slip(23.0), Slip(30.0), Slip(40.0))))
