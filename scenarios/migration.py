"""A detector that can move: Algorithm 2 migrates without stopping the old instance.

``pc1`` and ``pc2`` (400 MB each) can both host ``force_slip_detector`` (150 MB); the
``tactile_slip_detector`` (300 MB) is fixed to ``pc2`` (EXECUTABLE_ON). In ``hold`` the
selector wants the force detector, in ``move_base`` both.

Paper bugs this shows (the checker finds the shortest runs):

* Algorithm 2 lines 16-18: when ``pc1`` goes down (or fills up) the force detector is
  started on ``pc2`` and the instance on ``pc1`` is never stopped: ``single-instance``;
* Algorithm 1 lines 5-8: a fixed deployment is started on its platform without checking
  its requirements: ``no-overcommit`` once the migrated force detector sits on ``pc2``;
* Algorithm 2 ignores EXECUTABLE_ON too, but here the fixed detector has nowhere to
  go (only ``pc2`` has a tactile pad): ``fixed`` holds (``scenarios/fixed_platform.py``
  shows that bug).

Run it: ``python scenarios/migration.py [paper]``.
"""

from __future__ import annotations

from desmon.model import HOLD, MOVE_BASE, RobotBuilder
from desmon.model.events import ActionChange
from desmon.model.scenario import Scenario, TimedEvent
from desmon.verify.bounds import Bounds, levels

FORCE = "force_slip_detector"
TACTILE = "tactile_slip_detector"

robot = RobotBuilder("care-o-bot-3")
robot.platform("pc1", memory=400).device("wrench_1", kind="force_sensor")
robot.platform("pc2", memory=400).device("wrench_2", kind="force_sensor").device("pad", kind="tactile_pad")

with robot.rpsl.perception_graph(FORCE) as g:
    g.sensor("wrench", reads="force_sensor")
    g.processing("force_threshold", inputs=["wrench"])
with robot.rpsl.perception_graph(TACTILE) as g:
    g.sensor("pads", reads="tactile_pad")
    g.processing("tactile_threshold", inputs=["pads"])

robot.depsl.deployment_specification(FORCE).add_constraint("attribute", "platform_has", "force_sensor").add_constraint("capacity", "memory", 150)
robot.depsl.deployment_specification(TACTILE).add_constraint("quantity", "tactile_pad", 1).add_constraint("capacity", "memory", 300).executable_on("pc2")
robot.rules({HOLD: FORCE, MOVE_BASE: [FORCE, TACTILE]})

scenario = Scenario(
    name="migration",
    description="the force detector can run on pc1 or pc2; the tactile detector is fixed to pc2",
    model=robot.build(),
    timeline=(TimedEvent(0.0, ActionChange(HOLD), "t0"),),
    checker=Bounds(
        actions=(HOLD, MOVE_BASE),
        devices=("wrench_1",),
        platforms=("pc1", "pc2"),
        loads={"pc1": levels(0, 200, 100)},
        start_failures=1,
        max_failures=1,
    ),
    expected={
        "verify": {
            # desmon verify --continue: verdict, distinct states, shortest counterexample lengths
            "desmon": {"verdict": "HOLDS", "states": 54, "counterexamples": {}},
            "paper": {
                "verdict": "VIOLATED",
                "states": 189,
                "counterexamples": {
                    "valid-or-error": 1, "no-overcommit": 2, "single-instance": 1, "coverage": 1,
                    "errors-justified": 0, "preferred-when-possible": 1,
                },
            },
        },
    },
)

if __name__ == "__main__":
    from desmon.verify.report import run_script

    raise SystemExit(run_script(scenario))
