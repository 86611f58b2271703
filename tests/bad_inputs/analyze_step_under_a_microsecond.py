# args: analyze {case} --no-progress
# exit: 2
# expect: World task: the grasp steps last 1e-07 s on average, under the microsecond the detection trials time slips to: give them at least 1e-06 s
"""A bad-input case: see tests/test_bad_inputs.py. The coffee shift with a grasp of 0.1 microseconds: the
detection trials (which time steps to the microsecond) would have rendered it as no time at all."""
from dataclasses import replace
from pathlib import Path

from desmon.loader import load_scenario
from desmon.sim.world import Step, world_of

shift = load_scenario(Path(__file__).resolve().parent.parent.parent / "scenarios" / "coffee_shift.py", {"hours": "0.1"})
world = world_of(shift)
scenario = replace(shift, world=replace(world, task=tuple(Step(s.action, 1e-7) if s.action == "grasp" else s for s in world.task)))
