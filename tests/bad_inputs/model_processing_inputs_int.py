# args: verify {case}
# exit: 2
# expect: processing component 'tare' inputs = 5 is not a sequence
"""A bad-input case: see tests/test_bad_inputs.py. inputs= given a number."""
from desmon.model import RobotBuilder
robot = RobotBuilder()
with robot.rpsl.perception_graph('g') as g:
    g.sensor('w', reads='force_sensor')
    g.processing('tare', inputs=5)
