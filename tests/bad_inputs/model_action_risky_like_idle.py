# args: verify {case}
# exit: 2
# expect: action 'pour' is risky (an object in the hand) but like='idle' has an empty hand
"""A bad-input case: see tests/test_bad_inputs.py. ``risky`` and ``like`` disagree about the hand."""
from desmon.model.cob3 import care_o_bot
robot = care_o_bot()
robot.action('pour', risky=True, like='idle')
