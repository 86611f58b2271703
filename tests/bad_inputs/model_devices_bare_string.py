# args: verify {case}
# exit: 2
# expect: 'pad' is a single string
# expect: letter by letter
"""A bad-input case: see tests/test_bad_inputs.py. devices('pad') would create devices p, a, d."""
from desmon.model import RobotBuilder
robot = RobotBuilder()
robot.platform('hand_pc', memory=256).devices('pad', kind='tactile_pad')
