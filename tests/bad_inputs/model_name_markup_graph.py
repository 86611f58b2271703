# args: show {case} --format dot -o {tmp}/out.dot
# exit: 2
# expect: perception graph '<b>slip</b>' contains '<' (U+003C): write a name of letters, digits, '_', '-' or '.' only
# untouched: {tmp}/out.dot
"""A bad-input case: see tests/test_bad_inputs.py. A perception graph named with markup: refused when the model is
built (the name would be markup in the explorer's page and a tag in GraphML)."""
from desmon.model import RobotBuilder
robot = RobotBuilder('r')
with robot.rpsl.perception_graph('<b>slip</b>') as g:
    g.sensor('wrench', reads='force_sensor')
