"""Two interchangeable edge boxes, four detectors that fit one to a box, two failing starts
a transition: the deployer's memory of where a start failed, by platform name, against a
tie-break between equal boxes.

While the robot holds, ``g`` (fallback ``z_fallback``) and ``p`` (fallback ``fy``) are
wanted; on a grasp ``h`` comes first. When the boxes are full, ``h`` finds no room; the
upgrade stops ``z_fallback``, and ``g`` and then ``z_fallback`` fail to start on the box
it freed; ``p`` starts on ``big``, which frees the other box from ``fy``. The reaction's
second chance then gives ``h`` the first box by declaration, and ``g`` the other one,
unless the other one is where ``g``'s start just failed: which it is depends on which box
held ``z_fallback``, so two states that differ only by the boxes' names end differently.
"""

from desmon.model import GRASP, HOLD, RobotBuilder
from desmon.model.events import ActionChange
from desmon.model.scenario import Scenario, TimedEvent
from desmon.verify.bounds import Bounds

robot = RobotBuilder("r")
robot.platform("a1", memory=200, attributes={"edge": "yes"})
robot.platform("a2", memory=200, attributes={"edge": "yes"})
robot.platform("big", memory=1000, attributes={"edge": "no"})
for name in ("h", "g", "z_fallback", "fy", "p"):
    with robot.rpsl.perception_graph(name) as graph:
        graph.sensor("input", reads="camera")
        graph.processing("detect", inputs=["input"])
for name in ("h", "g", "z_fallback", "fy"):
    robot.depsl.deployment_specification(name).add_constraint("attribute", "edge", "yes").add_constraint("capacity", "memory", 150)
robot.depsl.deployment_specification("p").add_constraint("attribute", "edge", "no").add_constraint("capacity", "memory", 100)
robot.rules({HOLD: [("g", "z_fallback"), ("p", "fy")], GRASP: ["h", ("g", "z_fallback"), ("p", "fy")]})

scenario = Scenario(
    name="second_chance_memory",
    description="a failed start's memory by platform name against a tie-break between interchangeable boxes",
    model=robot.build(),
    timeline=(TimedEvent(0.0, ActionChange(HOLD), "the robot holds"),),
    checker=Bounds(actions=(HOLD, GRASP), platforms=("big", "a1", "a2"), max_failures=2, start_failures=2, interchangeable=(("a1", "a2"),)),
)
