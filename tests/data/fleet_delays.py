"""Two robots ``a`` and ``b`` checked together (sharing ``edge0``), each with its own World:
its own notice delay (``-p hb_a=``, ``-p hb_b=``); the checker's bounds fail the camera of
one of them (``-p failing=a`` or ``b``). A third robot ``c`` (``-p with_c=True``) runs in the
fleet with long delays, but is not in the checked model.
"""

from desmon.model import RobotBuilder
from desmon.model.events import ActionChange
from desmon.model.params import parameters
from desmon.model.scenario import Scenario, TimedEvent
from desmon.sim.fleet import Fleet, merged_model
from desmon.sim.world import Step, World
from desmon.verify.bounds import Bounds

p = parameters(hb_a=2.0, hb_b=0.0, failing="b", with_c=False)


def robot(name: str, heartbeat: float) -> Scenario:
    r = RobotBuilder(name)
    r.platform(f"{name}.pc", memory=512).device(f"{name}.cam", kind="camera")
    r.platform("edge0", memory=512)
    with r.rpsl.perception_graph(f"{name}.g") as graph:
        graph.sensor("s", reads="camera")
        graph.processing("p", inputs=["s"])
    r.depsl.deployment_specification(f"{name}.g").add_constraint("capacity", "memory", 50)
    r.rules({"hold": f"{name}.g"})
    world = World(task=(Step("hold", 20.0),), horizon=20.0, signals=False, heartbeat_timeout=heartbeat, start_latency=9.0 if name == "c" else 0.0)
    return Scenario(name=name, model=r.build(), timeline=(TimedEvent(0.0, ActionChange("hold"), "t0"),), world=world)


robots = [robot("a", p.hb_a), robot("b", p.hb_b)] + ([robot("c", 9.0)] if p.with_c else [])
scenario = Scenario(
    name="fleet_delays",
    model=merged_model((r.model for r in robots[:2]), ("edge0",)),
    timeline=(TimedEvent(0.0, ActionChange("hold"), "t0"),),
    world=Fleet(robots=tuple(robots), edges=("edge0",)),
    checker=Bounds(actions=("hold",), devices=(f"{p.failing}.cam",), platforms=("edge0",) if p.with_c else ()),
)
