"""A platform comes back as another goes down, at one instant: never two down at once.

``grasp`` wants ``u`` and one of the slot ``(g, f)``; ``u`` and ``g`` need 100 MB each
(``A``, ``B``), the fallback ``f`` fits on ``C`` only. ``A`` goes down at 5 s; at 10 s it
is back *and* ``B`` crashes. Under ``max_failures=1`` that pair is within the budget
(after it one platform is down, as before), and the world's deployer answers both in one
reaction: the ``make-before-break`` mutant then starts ``g`` on ``A`` before it stops
``g`` on ``B``, which ``single-instance`` reports right after the start.
"""

from desmon.model import RobotBuilder
from desmon.model.events import ActionChange, PlatformDown, PlatformUp
from desmon.model.params import parameters
from desmon.model.scenario import Scenario, TimedEvent
from desmon.sim.world import Step, World
from desmon.verify.bounds import Bounds

p = parameters(max_failures=1, t_swap=10.0)

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
    name="swap_at_one_instant",
    model=robot.build(),
    timeline=(TimedEvent(0.0, ActionChange("grasp"), "t0"),),
    world=World(
        task=(Step("grasp", 20.0),), horizon=20.0, signals=False,
        faults=(TimedEvent(5.0, PlatformDown("A")), TimedEvent(p.t_swap, PlatformUp("A")), TimedEvent(10.0, PlatformDown("B")),
                TimedEvent(15.0, PlatformUp("B"))),
    ),
    checker=Bounds(actions=("grasp",), platforms=("A", "B"), max_failures=p.max_failures),
)
