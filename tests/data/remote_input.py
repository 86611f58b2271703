"""A test scenario where the Control rules refuse starts: a detector on the torso reads the
arm's wrench, and the arm PC is down from the start (``-p arm_down=false``: it is up, and
only the checker's chosen start failures make starts fail).

``static`` is a deliberately naive deployer: it starts every wanted detector on a fixed
platform and never raises an error, so any start that fails -- refused by the Control
rules or chosen to fail by the checker -- breaks ``coverage``. The tests of
counterexample reports use it to tell the two apart (tests/test_counterexample_starts.py).
"""

from desmon.deployment.deployer import Deployer
from desmon.deployment.ports import Start, Stop
from desmon.model import GRASP, HOLD, RobotBuilder
from desmon.model.events import ActionChange, PlatformDown
from desmon.model.params import parameters
from desmon.model.scenario import Scenario, TimedEvent
from desmon.verify.bounds import Bounds

p = parameters(arm_down=True)
COMBINED, TACTILE = "combined", "tactile"
HOME = {COMBINED: "torso_pc", TACTILE: "hand_pc"}

robot = RobotBuilder("r")
robot.platform("arm_pc", memory=100).device("wrench", kind="force_sensor")
robot.platform("hand_pc", memory=400).devices(["pad_1", "pad_2"], kind="tactile_pad")
robot.platform("torso_pc", memory=1000)
with robot.rpsl.perception_graph(COMBINED) as g:
    g.sensor("w", reads="force_sensor")
    g.sensor("t", reads="tactile_pad")
    g.processing("fuse", inputs=["w", "t"])
with robot.rpsl.perception_graph(TACTILE) as g:
    g.sensor("t", reads="tactile_pad")
robot.depsl.deployment_specification(COMBINED).add_constraint("capacity", "memory", 300)
robot.depsl.deployment_specification(TACTILE).add_constraint("quantity", "tactile_pad", 2).add_constraint("capacity", "memory", 100)
robot.rules({GRASP: [COMBINED, TACTILE]})

scenario = Scenario(
    name="remote_input",
    description="the combined detector on the torso reads the wrench of an arm PC that is down",
    model=robot.build(),
    initial=(PlatformDown("arm_pc"),) if p.arm_down else (),
    timeline=(TimedEvent(0.0, ActionChange(HOLD), "t0"), TimedEvent(1.0, ActionChange(GRASP), "t1")),
    checker=Bounds(actions=(HOLD, GRASP), start_failures=1),
)


def _static(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    wanted = {g for slot in slots for g in slot[:1]}
    for g, p in q.deployments():
        if g not in wanted:
            yield Stop(g, p)
    for slot in slots:
        g = slot[0]
        if not q.deployed_on(g):
            yield Start(g, HOME[g])  # whatever happens, no error is raised


static = Deployer("static", "starts every wanted detector on a fixed platform and never raises an error", _static)
