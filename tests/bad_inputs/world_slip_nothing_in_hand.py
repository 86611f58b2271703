# args: run {case}
# exit: 2
# expect: slip at t=3 falls in 'idle', when no object is in the hand
"""A bad-input case: see tests/test_bad_inputs.py. A slip with nothing in the hand (with signals off it counted as injected)."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.sim.world import Slip, Step, World
scenario = Scenario(name='bad', model=care_o_bot().build(), world=World(task=(Step('idle', 5.0), Step('grasp', 2.0), Step('hold', 3.0)), horizon=10.0, slips=(Slip(3.0),)))
