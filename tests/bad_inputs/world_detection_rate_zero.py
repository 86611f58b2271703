# args: run {case}
# exit: 2
# expect: a rate of 0.0: give a probability above 0
"""A bad-input case: see tests/test_bad_inputs.py. A rate of 0 says nothing a missing rate does not: refused."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.sim.world import Step, World

scenario = Scenario(name='bad', model=care_o_bot().build(), world=World(task=(Step('grasp', 2.0), Step('hold', 8.0)), horizon=10.0, detection_rates={'tactile_slip_detector': 0.0}))
