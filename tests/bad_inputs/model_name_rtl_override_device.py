# args: explore {case} -o {tmp}/page.html
# exit: 2
# expect: device 'pad\u202e_1' contains '\u202e' (U+202E): write a name of letters, digits, '_', '-' or '.' only
# untouched: {tmp}/page.html
"""A bad-input case: see tests/test_bad_inputs.py. A device name holding a right-to-left override, which would show
the name reversed: refused when the model is built, the invisible character shown."""
from desmon.model import RobotBuilder
robot = RobotBuilder('r')
robot.platform('hand_pc', memory=512).device('pad\u202e_1', kind='tactile_pad')
