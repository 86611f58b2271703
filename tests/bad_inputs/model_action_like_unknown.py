# args: verify {case}
# exit: 2
# expect: like='hlod' is not a built-in action (did you mean 'hold'?)
"""A bad-input case: see tests/test_bad_inputs.py. ``like`` naming no action at all."""
from desmon.model.cob3 import care_o_bot
robot = care_o_bot()
robot.action('pour', risky=True, like='hlod')
