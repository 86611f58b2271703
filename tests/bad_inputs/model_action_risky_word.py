# args: verify {case}
# exit: 2
# expect: action 'pour' risky = 'yes' is not True or False
"""A bad-input case: see tests/test_bad_inputs.py. ``risky`` written as a word."""
from desmon.model.cob3 import care_o_bot
robot = care_o_bot()
robot.action('pour', risky='yes')
