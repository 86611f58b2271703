# args: run {case}
# exit: 2
# expect: detection_rates gives 'force_slip_detector' a rate, but every input it reads has a signal model
"""A bad-input case: see tests/test_bad_inputs.py. A rate given for a detector whose rate desmon measures from its signals."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.sim.world import Step, World

scenario = Scenario(name='bad', model=care_o_bot().build(), world=World(task=(Step('grasp', 2.0), Step('hold', 8.0)), horizon=10.0, detection_rates={'force_slip_detector': 0.9}))
