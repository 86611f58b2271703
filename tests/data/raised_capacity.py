"""A requirement change raises a running graph's Capacity above its platform's capacity:
the platform is over-committed by the environment, before the deployer reacts. Its
reaction stops both graphs of the platform, one after the other; ``-p other=NAME``
names the second graph, which decides the order of the stops.
"""

from desmon.deployment.deployer import DESMON, Deployer
from desmon.deployment.ports import Start, Stop
from desmon.model import RobotBuilder
from desmon.model.events import ActionChange, RequirementChange
from desmon.model.params import parameters
from desmon.model.requirements import Capacity
from desmon.model.scenario import Scenario, TimedEvent
from desmon.sim.world import Step, World
from desmon.verify.bounds import Bounds

p = parameters(other="a_graph")

robot = RobotBuilder("r")
robot.platform("pc", memory=384)
robot.platform("arm", memory=10).device("ft", kind="force_sensor")
for name in ("m_graph", p.other):
    with robot.rpsl.perception_graph(name) as graph:
        graph.sensor("s", reads="force_sensor")
        graph.processing("p", inputs=["s"])
robot.depsl.deployment_specification("m_graph").add_constraint("capacity", "memory", 100)
robot.depsl.deployment_specification(p.other).add_constraint("capacity", "memory", 200)
UP = RequirementChange("m_graph", add=(Capacity("memory", 400),), remove=(Capacity("memory", 100),), label="up")
robot.rules({"hold": ["m_graph", p.other]})

scenario = Scenario(
    name="raised_capacity",
    model=robot.build(),
    timeline=(TimedEvent(0.0, ActionChange("hold"), "t0"),),
    world=World(task=(Step("hold", 10.0),), horizon=10.0, signals=False, changes=(TimedEvent(2.0, UP),)),
    checker=Bounds(actions=("hold",), requirement_changes=(UP,)),
)


def _restarts_first(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    """Re-issues a Start for every running instance (a no-op), then desmon's reaction."""
    for g, platform in q.deployments():
        yield Start(g, platform)
    yield from DESMON.react(q, slots, changed, context_changed)


restarts_first = Deployer("restarts-first", "re-issues the starts of running instances first", _restarts_first)


def _tries_the_arm_first(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    """Once pc is over-committed, tries the other graph on the arm's computer (over its
    capacity for a moment: the bug), stops it there, then desmon's reaction."""
    if any(g == "m_graph" and dict(use).get("memory", 0) > 384 for s in q.platform_states() for g, use in s.deployed):
        other = next(g for g, _p in q.deployments() if g != "m_graph")
        if (yield Start(other, "arm")):
            yield Stop(other, "arm")
    yield from DESMON.react(q, slots, changed, context_changed)


tries_the_arm_first = Deployer("tries-the-arm-first", "over-commits the arm's computer for a moment", _tries_the_arm_first)
