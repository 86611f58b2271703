# args: explain {case} force_slip_detector
# exit: 2
# expect: platform 'arm_pc' attribute 'platform_has' is the name Attribute('platform_has', KIND) reserves for an attached working device
"""A bad-input case: see tests/test_bad_inputs.py. The attribute was never read: the requirement asks for a device."""
from desmon.model import RobotBuilder
from desmon.model.scenario import Scenario

robot = RobotBuilder("r")
robot.platform("arm_pc", memory=512, attributes={"platform_has": "force_sensor"})
with robot.rpsl.perception_graph("force_slip_detector") as g:
    g.sensor("w", reads="force_sensor")
robot.depsl.deployment_specification("force_slip_detector").add_constraint("capacity", "memory", 100)
robot.rules({"hold": "force_slip_detector"})
scenario = Scenario(name="attr", model=robot.build())
