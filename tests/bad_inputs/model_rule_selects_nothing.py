# args: verify {case}
# exit: 2
# expect: rule for context 'grasp' selects nothing
"""A bad-input case: see tests/test_bad_inputs.py. An empty rule (wants no detector, silently)."""
from desmon.model.cob3 import care_o_bot
robot = care_o_bot(rules=False)
robot.rules({'grasp': [], 'release': 'force_slip_detector'})
