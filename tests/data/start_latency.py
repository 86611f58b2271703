"""A requirement change arrives while a start waits out its latency (``-p timing=...``).

``p0`` has 100 MB; ``g`` and ``h`` need 45 MB each and both watch ``hold``. At 1.5 s ``h``
needs 60 MB. With fixed timing the start of ``h`` issued at 1 s completes at 2 s on the
facts after the change: 105 MB on ``p0`` (the world books no-overcommit right after it),
a state the checker, which completes each start before the next event, never reaches. With
exponential timing a start is decided at once (only its readiness waits), so no change
comes inside one.
"""

from desmon.model import RobotBuilder
from desmon.model.events import ActionChange, RequirementChange
from desmon.model.params import parameters
from desmon.model.requirements import Capacity
from desmon.model.scenario import Scenario, TimedEvent
from desmon.sim.world import Step, World
from desmon.verify.bounds import Bounds

p = parameters(latency=1.0, timing="fixed")

robot = RobotBuilder("r")
robot.platform("p0", memory=100).device("cam", kind="camera")
for name in ("g", "h"):
    with robot.rpsl.perception_graph(name) as graph:
        graph.sensor("s", reads="camera")
        graph.processing("p", inputs=["s"])
    robot.depsl.deployment_specification(name).add_constraint("capacity", "memory", 45)
BIGGER = RequirementChange("h", add=(Capacity("memory", 60),), remove=(Capacity("memory", 45),), label="bigger")
robot.rules({"hold": ["g", "h"]})

scenario = Scenario(
    name="start_latency",
    model=robot.build(),
    timeline=(TimedEvent(0.0, ActionChange("hold"), "t0"),),
    world=World(
        task=(Step("hold", 20.0),), horizon=20.0, signals=False, start_latency=p.latency, timing=p.timing,
        changes=(TimedEvent(1.5, BIGGER),),
    ),
    checker=Bounds(actions=("hold",), requirement_changes=(BIGGER,)),
)
