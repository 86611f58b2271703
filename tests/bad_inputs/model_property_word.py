# args: verify {case}
# exit: 2
# expect: property 'speed' = 'fast' is not a number
# expect: symbolic facts in attributes
"""A bad-input case: see tests/test_bad_inputs.py. A word in numeric properties."""
from desmon.model import RobotBuilder
robot = RobotBuilder()
robot.platform('pc', properties={'speed': 'fast'})
