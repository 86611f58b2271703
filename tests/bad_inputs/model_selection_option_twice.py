# args: verify {case}
# exit: 2
# expect: Selection lists the option gpu=yes twice: list each alternative once
"""A bad-input case: see tests/test_bad_inputs.py. One fact counted twice towards at_least=2: the
platform was accepted with one of the two alternatives asked for."""
from desmon.model import RobotBuilder
from desmon.model.events import ActionChange
from desmon.model.scenario import Scenario, TimedEvent

robot = RobotBuilder("r")
robot.platform("a", memory=512, attributes={"gpu": "yes"}).device("ft", kind="force_sensor")
robot.platform("b", memory=512, attributes={"gpu": "no"}).device("cam", kind="camera")
with robot.rpsl.perception_graph("fsd") as g:
    g.sensor("w", reads="force_sensor")
robot.depsl.deployment_specification("fsd").add_constraint("selection", "gpu=yes", "gpu=yes", at_least=2)
robot.rules({"hold": "fsd"})
scenario = Scenario(name="seldup", model=robot.build(), timeline=(TimedEvent(0.0, ActionChange("hold"), "t0"),))
