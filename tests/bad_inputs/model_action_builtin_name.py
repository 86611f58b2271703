# args: verify {case}
# exit: 2
# expect: action 'hold' is built in: use it without declaring it
"""A bad-input case: see tests/test_bad_inputs.py. Declaring an action that is already built in."""
from desmon.model.cob3 import care_o_bot
robot = care_o_bot()
robot.action('hold', risky=True)
