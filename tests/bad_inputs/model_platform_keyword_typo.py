# args: verify {case}
# exit: 2
# expect: unknown keyword 'memroy'
# expect: did you mean 'memory'
"""A bad-input case: see tests/test_bad_inputs.py. A misspelt DSL keyword."""
from desmon.model import RobotBuilder
robot = RobotBuilder()
robot.platform('pc', memroy=512)
