# args: run {case} --seed 1 --no-progress
# exit: 2
# expect: world: scripted slips under timing='exponential': the task's steps move with the seed and 'idle' has no object in the hand
"""A bad-input case: see tests/test_bad_inputs.py. Checked against seed 0's layout only: other seeds
ended at run time, and with signals off the slip was injected with nothing in the hand."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.sim.world import Slip, Step, World
world = World(task=(Step('idle', 10.0), Step('grasp', 1.0), Step('hold', 5.0), Step('release', 1.0)), horizon=17.0,
              slips=(Slip(14.0),), timing='exponential')
scenario = Scenario(name='bad', model=care_o_bot().build(), world=world)
