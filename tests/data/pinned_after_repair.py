"""A deployer that starts its graph on ``p0`` whatever the repository says of ``p0``.

``p0`` hosts the force sensor and the detector ``g``; it fails (MTTF 60 s, MTTR 10 s), and
the monitor notices a crash or a reboot after ``heartbeat`` seconds on average. While the
repository still believes ``p0`` down after its reboot, ``pinned``'s start there succeeds
in the world, whose infrastructure judges a start on the facts as they are.
"""

from desmon.deployment.ports import Start, Stop
from desmon.model import RobotBuilder
from desmon.model.params import parameters
from desmon.model.scenario import Scenario
from desmon.sim.world import MTTF, Step, World
from desmon.verify.bounds import Bounds

p = parameters(heartbeat=20.0)

robot = RobotBuilder("r")
robot.platform("p0", memory=512).device("ft", kind="force_sensor")
robot.platform("p1", memory=512)
with robot.rpsl.perception_graph("g") as graph:
    graph.sensor("s", reads="force_sensor")
    graph.processing("p", inputs=["s"])
robot.depsl.deployment_specification("g").add_constraint("capacity", "memory", 50)
robot.rules({"hold": "g"})

scenario = Scenario(
    name="pinned_after_repair",
    model=robot.build(),
    world=World(
        task=(Step("hold", 3.0), Step("idle", 3.0)), repeat=True, horizon=600.0,
        stochastic_faults=(MTTF("p0", mttf=60.0, mttr=10.0),), heartbeat_timeout=p.heartbeat,
    ),
    checker=Bounds(task={"hold": ("idle",), "idle": ("hold",)}, initial_action="idle", platforms=("p0",)),
)


def pinned(q, slots, changed, context_changed):
    """Start every wanted graph on p0; stop what is not wanted."""
    wanted = {g for slot in slots for g in slot}
    for g, pl in q.deployments():
        if g not in wanted:
            yield Stop(g, pl)
    for g in sorted(wanted):
        if not q.deployed_on(g):
            yield Start(g, "p0")
