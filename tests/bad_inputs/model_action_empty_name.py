# args: verify {case}
# exit: 2
# expect: action '' is not a name
"""A bad-input case: see tests/test_bad_inputs.py. Declaring an action with an empty name."""
from desmon.model.cob3 import care_o_bot
robot = care_o_bot()
robot.action('', risky=True, like='hold')
