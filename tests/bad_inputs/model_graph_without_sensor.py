# args: verify {case}
# exit: 2
# expect: has no sensor component
"""A bad-input case: see tests/test_bad_inputs.py. A graph that reads nothing."""
from desmon.model import RobotBuilder
robot = RobotBuilder()
with robot.rpsl.perception_graph('g') as g:
    g.processing('tare', inputs='tare_in')
    g.processing('tare_in', inputs='tare')
