# args: verify {case}
# exit: 2
# expect: got 3 argument(s)
# expect: write ('capacity', resource, amount)
"""A bad-input case: see tests/test_bad_inputs.py. One argument too many."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
robot = care_o_bot(specs=False)
robot.depsl.deployment_specification('force_slip_detector').add_constraint('capacity', 'memory', 50, 'MB')
