# args: verify {case}
# exit: 2
# expect: preference = nan is not a number
"""A bad-input case: see tests/test_bad_inputs.py. NaN platform preference (orders nothing)."""
from desmon.model import RobotBuilder
robot = RobotBuilder()
robot.platform('pc', preference=float('nan'))
