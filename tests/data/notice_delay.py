"""A platform comes back while the monitor has not noticed yet (``-p heartbeat=S``, the
world's notice delay), and a requirement change makes the deployer react in between.

``p0`` hosts the only camera and ``g`` runs there; ``p0`` goes down at 5 s and is back
at 10 s, noticed ``heartbeat`` seconds later; at 10.2 s ``g`` gains a preference. A
deployer that left ``g`` on ``p0`` while it believed ``p0`` down starts it on ``p1`` then:
the start succeeds, since the camera is in fact back, and ``g`` runs twice.
"""

from desmon.model import RobotBuilder
from desmon.model.events import ActionChange, PlatformDown, PlatformUp, RequirementChange
from desmon.model.params import parameters
from desmon.model.requirements import Preference
from desmon.model.scenario import Scenario, TimedEvent
from desmon.sim.world import Step, World
from desmon.verify.bounds import Bounds

p = parameters(heartbeat=0.5)

robot = RobotBuilder("r")
robot.platform("p0", memory=512).device("cam", kind="camera")
robot.platform("p1", memory=512)
with robot.rpsl.perception_graph("g") as graph:
    graph.sensor("s", reads="camera")
    graph.processing("p", inputs=["s"])
robot.depsl.deployment_specification("g").add_constraint("capacity", "memory", 50)
SPREAD = RequirementChange("g", add=(Preference("spread", (), 1.0),), label="spread")
robot.rules({"hold": "g"})

scenario = Scenario(
    name="notice_delay",
    model=robot.build(),
    timeline=(TimedEvent(0.0, ActionChange("hold"), "t0"),),
    world=World(
        task=(Step("hold", 20.0),), horizon=20.0, signals=False, heartbeat_timeout=p.heartbeat,
        faults=(TimedEvent(5.0, PlatformDown("p0")), TimedEvent(10.0, PlatformUp("p0"))),
        changes=(TimedEvent(10.2, SPREAD),),
    ),
    checker=Bounds(actions=("hold",), platforms=("p0",), requirement_changes=(SPREAD,)),
)
