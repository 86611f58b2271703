"""Three identical edge computers: symmetry reduction (``--symmetry``) is accepted.

``e1``, ``e2``, ``e3`` are the same box (200 MB, one camera each), declared one after
the other and declared interchangeable in the checker bounds. The vision detector runs
on whichever is up; the slip model fits on any platform, but never beside the vision
detector on an edge box (120 + 150 MB > 200 MB), so an edge box hosts at most one
graph. The edge boxes may crash and reboot; their cameras never fail and carry no
background load. Those are the conditions under which the deployer's
first-acceptable-by-declaration tie-break is symmetric up to renaming (the soundness
argument is in :mod:`desmon.verify.symmetry`).

Run it: ``python scenarios/symmetric_platforms.py [--symmetry]`` or
``desmon verify scenarios/symmetric_platforms.py --symmetry``.

Parameters (``-p NAME=VALUE``): ``edges``, the number of edge computers (2 to 12, default 3), and
``max_failures``, how many faults may be present at once (default 2): ``-p edges=5 -p
max_failures=3`` makes a larger model of the same shape.
"""

from __future__ import annotations

from desmon.errors import ScenarioError
from desmon.model import GRASP, HOLD, MOVE_BASE, RELEASE, RobotBuilder
from desmon.model.events import ActionChange, LoadChange
from desmon.model.params import parameters
from desmon.model.scenario import Scenario, TimedEvent
from desmon.verify.bounds import Bounds, levels

FORCE = "force_slip_detector"
TACTILE = "tactile_slip_detector"
VISION = "vision_slip_detector"
MODEL = "slip_model"
p = parameters(edges=3, max_failures=2)
if not 2 <= p.edges <= 12:
    raise ScenarioError(f"edges = {p.edges}: give a whole number of edge computers in [2, 12] (interchangeable needs two)")
EDGES = tuple(f"e{i}" for i in range(1, p.edges + 1))

robot = RobotBuilder("care-o-bot-3")
robot.platform("arm_pc", memory=512).device("wrench", kind="force_sensor")
robot.platform("hand_pc", memory=256).devices(["pad_1", "pad_2"], kind="tactile_pad")
for i, e in enumerate(EDGES, 1):
    robot.platform(e, memory=200).device(f"cam_{i}", kind="camera")

for name, reads in ((FORCE, "force_sensor"), (TACTILE, "tactile_pad"), (VISION, "camera"), (MODEL, "force_sensor")):
    with robot.rpsl.perception_graph(name) as g:
        g.sensor("input", reads=reads)
        g.processing("detect", inputs=["input"])

robot.depsl.deployment_specification(FORCE).add_constraint("attribute", "platform_has", "force_sensor").add_constraint("capacity", "memory", 100)
robot.depsl.deployment_specification(TACTILE).add_constraint("quantity", "tactile_pad", 2).add_constraint("capacity", "memory", 100)
robot.depsl.deployment_specification(VISION).add_constraint("attribute", "platform_has", "camera").add_constraint("capacity", "memory", 150)
robot.depsl.deployment_specification(MODEL).add_constraint("capacity", "memory", 120)
robot.rules({HOLD: [FORCE, VISION], GRASP: [FORCE, TACTILE, VISION], MOVE_BASE: [VISION, MODEL], RELEASE: [(FORCE, MODEL)]})

scenario = Scenario(
    name="symmetric_platforms",
    description="three interchangeable edge computers host the vision detector; symmetry reduction applies",
    model=robot.build(),
    initial=(LoadChange("arm_pc", 0),),
    timeline=(TimedEvent(0.0, ActionChange(HOLD), "t0"),),
    checker=Bounds(
        actions=(HOLD, GRASP, MOVE_BASE, RELEASE),
        devices=("wrench", "pad_1"),
        platforms=("arm_pc", *EDGES),
        loads={"arm_pc": levels(0, 400, 100)},
        start_failures=1,
        max_failures=p.max_failures,
        interchangeable=(EDGES,),
    ),
    expected={
        "verify": {
            # desmon verify --continue [--symmetry]: verdict, distinct states
            "desmon": {"verdict": "HOLDS", "states": 1748, "counterexamples": {}},
            "desmon --symmetry": {"verdict": "HOLDS", "states": 475, "counterexamples": {}},
        },
    },
)

if __name__ == "__main__":
    import sys

    from desmon.verify.checker import Checker
    from desmon.verify.report import format_result

    result = Checker(scenario, "desmon", symmetry="--symmetry" in sys.argv).run(keep_going=True)
    print(format_result(result), end="")
    sys.exit(result.exit_code)
