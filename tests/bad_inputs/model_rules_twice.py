# args: verify {case}
# exit: 2
# expect: rules(...) is called twice
"""A bad-input case: see tests/test_bad_inputs.py. A second rules() call used to replace the first silently."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
robot = care_o_bot()
robot.rules({'hold': 'force_slip_detector'})
