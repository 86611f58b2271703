# args: show {case} --format cypher -o {tmp}/out.cypher
# exit: 2
# expect: contains "'" (U+0027): write a name of letters, digits, '_', '-' or '.' only
# untouched: {tmp}/out.cypher
"""A bad-input case: see tests/test_bad_inputs.py. An attribute name holding a quote (which would end a string in a
Cypher script): refused when the model is built."""
from desmon.model import RobotBuilder
robot = RobotBuilder('r')
robot.platform('arm_pc', memory=512, attributes={"o's": 'linux'})
