# args: verify {case}
# exit: 2
# expect: action 'drizzle': like='pour' is not a built-in action
"""A bad-input case: see tests/test_bad_inputs.py. ``like`` naming a declared action (signal models exist for the built-ins only)."""
from desmon.model.cob3 import care_o_bot
robot = care_o_bot()
robot.action('pour', risky=True, like='hold')
robot.action('drizzle', risky=True, like='pour')
