"""Two edge computers declared interchangeable, e1 with ``gen=1`` and e2 with the ``gen``
value ``-p e2_gen=int|float|str`` writes as ``1``, ``1.0`` or ``"1"``; both graphs require
``Attribute("gen", 1)``, which compares as text: only ``1`` and ``"1"`` meet it.
``-p start_failures=1`` lets a start fail: ``det_b`` may then start on the box where
``det_a``'s start just failed, a reaction ``--symmetry`` refuses (tests/test_symmetry.py).
"""

from desmon.model import HOLD, IDLE, MOVE_BASE, RobotBuilder
from desmon.model.events import ActionChange
from desmon.model.params import parameters
from desmon.model.scenario import Scenario, TimedEvent
from desmon.verify.bounds import Bounds

p = parameters(e2_gen="int", start_failures=0)
E2_GEN = {"int": 1, "float": 1.0, "str": "1"}[p.e2_gen]

robot = RobotBuilder("r")
robot.platform("main_pc", memory=400, attributes={"gen": "0"}).device("camera", kind="camera")
robot.platform("e1", memory=200, attributes={"gen": 1})
robot.platform("e2", memory=200, attributes={"gen": E2_GEN})
for name in ("det_a", "det_b"):
    with robot.rpsl.perception_graph(name) as g:
        g.sensor("cam", reads="camera")
        g.processing("p", inputs=["cam"])
    robot.depsl.deployment_specification(name).add_constraint("attribute", "gen", 1).add_constraint("capacity", "memory", 150)
robot.rules({HOLD: "det_a", MOVE_BASE: ["det_a", "det_b"]})

scenario = Scenario(
    name="attribute_spelling",
    model=robot.build(),
    timeline=(TimedEvent(0.0, ActionChange(HOLD), "t0"),),
    checker=Bounds(actions=(IDLE, HOLD, MOVE_BASE), platforms=("e1", "e2"), start_failures=p.start_failures, interchangeable=(("e1", "e2"),)),
)
