# args: verify {case}
# exit: 2
# expect: 'force_sensor' left over
# expect: kind=... 
"""A bad-input case: see tests/test_bad_inputs.py. A keyword-only argument given by position."""
from desmon.model import RobotBuilder
robot = RobotBuilder()
robot.platform('pc', memory=512).device('ft', 'force_sensor')
