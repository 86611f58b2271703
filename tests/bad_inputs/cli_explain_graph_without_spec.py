# args: explain {case} fsd --at t0
# exit: 2
# expect: perception graph 'fsd' has no deployment specification, so nothing to explain; the scenario gives none
"""A bad-input case: see tests/test_bad_inputs.py. The refusal had ended in "known: " and an empty list."""
from desmon.model import RobotBuilder
from desmon.model.events import ActionChange
from desmon.model.scenario import Scenario, TimedEvent

robot = RobotBuilder("r")
robot.platform("a", memory=512).device("ft", kind="force_sensor")
robot.platform("b", memory=512)
with robot.rpsl.perception_graph("fsd") as g:
    g.sensor("w", reads="force_sensor")
    g.processing("t", inputs=["w"])

scenario = Scenario(
    name="base", model=robot.build(),
    timeline=(TimedEvent(0.0, ActionChange("grasp"), "t0"), TimedEvent(1.0, ActionChange("hold"), "t1")),
)
