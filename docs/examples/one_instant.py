"""One reaction of the world answers two changes: the robot's next step and a platform's crash.

In ``grasp`` the selector wants ``u`` and one of the slot ``(g, f)``; in ``hold`` only the
slot. ``u`` and ``g`` need 100 MB each, so they run on ``A`` and ``B``; the fallback
``f`` fits on ``C`` only. At 10 s the robot starts to hold *and* ``B`` crashes, at the
same instant (``-p t_fault=10.001`` parts them): the world's deployer takes both in one
reaction, with ``context_changed`` and ``changed=("B",)``. The checker's transitions
carry one change each, and its verdict says so; ``desmon verify --together`` (or ``-p
together=True``) also explores two changes answered by one reaction.

    desmon run docs/examples/one_instant.py --deployer mutant:recheck-first      # exit 1
    desmon verify docs/examples/one_instant.py --deployer mutant:recheck-first --together
"""

from desmon.model import RobotBuilder
from desmon.model.events import ActionChange, PlatformDown, PlatformUp
from desmon.model.params import parameters
from desmon.model.scenario import Scenario, TimedEvent
from desmon.sim.world import Step, World
from desmon.verify.bounds import Bounds

p = parameters(t_fault=10.0, latency=0.0, together=False)

robot = RobotBuilder("r")
robot.platform("A", memory=100, attributes={"big": "yes"})
robot.platform("B", memory=100, attributes={"big": "yes"})
robot.platform("C", memory=20, attributes={"big": "no"})
for name in ("g", "u", "f"):
    with robot.rpsl.perception_graph(name) as graph:
        graph.sensor("s", reads="force_sensor")
        graph.processing("p", inputs=["s"])
robot.depsl.deployment_specification("g").add_constraint("capacity", "memory", 100)
robot.depsl.deployment_specification("u").add_constraint("capacity", "memory", 100)
robot.depsl.deployment_specification("f").add_constraint("capacity", "memory", 10).add_constraint("attribute", "big", "no")
robot.rules({"grasp": ["u", ("g", "f")], "hold": [("g", "f")]})

scenario = Scenario(
    name="combined_stimulus",
    model=robot.build(),
    timeline=(TimedEvent(0.0, ActionChange("grasp"), "t0"),),
    world=World(
        task=(Step("grasp", 10.0), Step("hold", 10.0)), horizon=20.0, signals=False, start_latency=p.latency,
        faults=(TimedEvent(p.t_fault, PlatformDown("B")), TimedEvent(15.0, PlatformUp("B"))),
    ),
    checker=Bounds(task={"grasp": ("hold",), "hold": ()}, initial_action="grasp", platforms=("B",), together=p.together),
)
