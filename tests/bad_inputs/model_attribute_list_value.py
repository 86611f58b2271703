# args: verify {case}
# exit: 2
# expect: attribute 'gpu' = [1] is not a string or a number
"""A bad-input case: see tests/test_bad_inputs.py. A list where a scalar belongs."""
from desmon.model import RobotBuilder
robot = RobotBuilder()
robot.platform('pc', attributes={'gpu': [1]})
