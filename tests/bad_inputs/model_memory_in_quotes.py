# args: verify {case}
# exit: 2
# expect: platform 'arm_pc'
# expect: '512' is a string, not a number
# expect: without quotes
"""A bad-input case: see tests/test_bad_inputs.py. A number written in quotes."""
from desmon.model import RobotBuilder
robot = RobotBuilder()
robot.platform('arm_pc', memory='512')
