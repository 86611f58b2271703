# args: verify {case}
# exit: 2
# expect: sensor component 'w' reads none is not a name
"""A bad-input case: see tests/test_bad_inputs.py. reads=None."""
from desmon.model import RobotBuilder
robot = RobotBuilder()
with robot.rpsl.perception_graph('g') as g:
    g.sensor('w', reads=None)
