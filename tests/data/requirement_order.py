"""One graph, one computer, and four requirement changes that only ever add or remove:
the Capacity it declared first goes and comes back, a Minimum and a Maximum are added.
Every requirement set is met on the computer, so the set alone decides the state: the
changes reach 2 x 2 x 2 = 8 sets, whatever order they come in.
"""

from desmon.model import RobotBuilder
from desmon.model.events import RequirementChange
from desmon.model.requirements import Attribute, Capacity, Maximum, Minimum
from desmon.model.scenario import Scenario
from desmon.verify.bounds import Bounds

CAP, ATTR = Capacity("memory", 100), Attribute("os", "linux")
MIN, MAX = Minimum("cores", 2), Maximum("link_latency_ms", 5)

DROP = RequirementChange("g", remove=(CAP,), label="drop the capacity")
BACK = RequirementChange("g", add=(CAP,), label="the capacity back")
ADD_MIN = RequirementChange("g", add=(MIN,), label="a minimum")
ADD_MAX = RequirementChange("g", add=(MAX,), label="a maximum")

robot = RobotBuilder("r")
robot.platform("pc", memory=512, attributes={"os": "linux"}, properties={"cores": 4, "link_latency_ms": 1.0}).device("ft", kind="force_sensor")
with robot.rpsl.perception_graph("g") as graph:
    graph.sensor("s", reads="force_sensor")
robot.depsl.deployment_specification("g").require(CAP).require(ATTR)
robot.rules({"hold": ["g"]})

scenario = Scenario(
    name="requirement_order",
    model=robot.build(),
    checker=Bounds(initial_action="hold", requirement_changes=(DROP, BACK, ADD_MIN, ADD_MAX)),
)
