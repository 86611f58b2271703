# args: verify {case}
# exit: 2
# expect: action 'pick up' contains a space: write a name of letters, digits, '_', '-' or '.' only
"""A bad-input case: see tests/test_bad_inputs.py. An action named with a space: the same rule as every name."""
from desmon.model.cob3 import care_o_bot
robot = care_o_bot()
robot.action('pick up', risky=True, like='hold')
