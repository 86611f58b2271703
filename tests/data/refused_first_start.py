"""The only force sensor has failed before the first reaction, so the Control rules refuse
the start of ``g`` on ``b`` (its input is unreadable) in every run: no choice of the
checker and no failure of the world's. ``raises`` fails when a start does not work, so
it cannot run at all in this scenario."""

from desmon.deployment.deployer import Deployer
from desmon.deployment.ports import Start
from desmon.model import RobotBuilder
from desmon.model.events import ActionChange, DeviceFail
from desmon.model.scenario import Scenario, TimedEvent
from desmon.sim.world import Step, World
from desmon.verify.bounds import Bounds

robot = RobotBuilder("r")
robot.platform("b", memory=512).device("ft", kind="force_sensor")
with robot.rpsl.perception_graph("g") as graph:
    graph.sensor("s", reads="force_sensor")
    graph.processing("p", inputs=["s"])
robot.depsl.deployment_specification("g").add_constraint("capacity", "memory", 100)
robot.rules({"hold": "g"})

scenario = Scenario(
    name="refused_first_start",
    model=robot.build(),
    initial=(DeviceFail("ft"),),
    timeline=(TimedEvent(0.0, ActionChange("hold"), "t0"),),
    world=World(task=(Step("hold", 5.0),), horizon=5.0, signals=False),
    checker=Bounds(task={"hold": ()}, initial_action="hold", start_failures=1),
)


def _raises(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    if q.deployed_on("g"):
        return
    ok = yield Start("g", "b")
    if not ok:
        raise RuntimeError("a start did not work")


raises = Deployer("raises", "raises when a start does not work", _raises)
