# args: show {case} --format graphml -o {tmp}/out.graphml
# exit: 2
# expect: platform 'arm\x00pc' contains '\x00' (U+0000): write a name of letters, digits, '_', '-' or '.' only
# untouched: {tmp}/out.graphml
"""A bad-input case: see tests/test_bad_inputs.py. A platform name holding a NUL byte: refused when the model is
built, naming it with the NUL shown, before GraphML (where a NUL cannot be written) is written."""
from desmon.model import RobotBuilder
robot = RobotBuilder('r')
robot.platform('arm\x00pc', memory=512)
