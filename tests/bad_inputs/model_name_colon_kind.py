# args: verify {case}
# exit: 2
# expect: device 'cam' kind 'camera:rgb' contains ':' (U+003A): write a name of letters, digits, '_', '-' or '.' only
"""A bad-input case: see tests/test_bad_inputs.py. A device kind holding a colon: kinds follow the rule of every name."""
from desmon.model.cob3 import care_o_bot
robot = care_o_bot()
robot.platform('head_pc', memory=256).device('cam', kind='camera:rgb')
