# args: explore {case} -o {tmp}/page.html
# exit: 2
# expect: contains 'ㅤ' (U+3164): write a name of letters, digits, '_', '-' or '.' only
# untouched: {tmp}/page.html
"""A bad-input case: see tests/test_bad_inputs.py. A platform name holding a Hangul filler, a letter that shows as
blank space (two platforms 'arm_pc' and 'arm_pc' + filler would look the same): refused, its code point shown."""
from desmon.model import RobotBuilder
robot = RobotBuilder('r')
robot.platform('arm_pc\u3164', memory=512)
