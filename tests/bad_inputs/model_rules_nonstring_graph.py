# args: verify {case}
# exit: 2
# expect: rule context 5 is a number
"""A bad-input case: see tests/test_bad_inputs.py. A rule keyed by a number."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
robot = care_o_bot(rules=False)
robot.rules({5: 'force_slip_detector'})
