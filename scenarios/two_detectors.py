"""Two detectors at once: in ``grasp`` the selector wants the force AND the tactile detector.

Platforms: ``arm_pc`` (512 MB, the KUKA wrench = force sensor) and ``hand_pc`` (384 MB,
two tactile pads). Rules: grasp -> force + tactile (two slots), release -> force,
move_base -> tactile, hold -> nothing.

The paper's Algorithm 1 returns after the first graph it starts (line 8), so in
``grasp`` the tactile detector is never deployed and no error says why: ``coverage``
fails one step after the initial state. The corrected ``desmon`` deployer holds.

On the SimPy world (``desmon run scenarios/two_detectors.py --deployer paper``) the
same early return leaves the tactile slot uncovered for the whole grasp: the force slot
being covered does not hide it, so all 5 s of risky time are unmonitored exposure and
the audit reports ``coverage``.

Run it: ``python scenarios/two_detectors.py [paper]`` (the checker, printed report).
"""

from __future__ import annotations

from desmon.model import GRASP, HOLD, MOVE_BASE, RELEASE, RobotBuilder
from desmon.model.events import ActionChange, LoadChange
from desmon.model.scenario import Scenario, TimedEvent
from desmon.verify.bounds import Bounds

FORCE = "force_slip_detector"
TACTILE = "tactile_slip_detector"

robot = RobotBuilder("care-o-bot-3")
robot.platform("arm_pc", memory=512).device("lwr_wrench", kind="force_sensor", vendor="kuka")
robot.platform("hand_pc", memory=384).devices(["pad_1", "pad_2"], kind="tactile_pad", vendor="weiss")

with robot.rpsl.perception_graph(FORCE) as g:
    g.sensor("wrench", reads="force_sensor")
    g.processing("force_threshold", inputs=["wrench"])
with robot.rpsl.perception_graph(TACTILE) as g:
    g.sensor("pads", reads="tactile_pad")
    g.processing("tactile_threshold", inputs=["pads"])

robot.depsl.deployment_specification(FORCE).add_constraint("attribute", "platform_has", "force_sensor").add_constraint("capacity", "memory", 50)
robot.depsl.deployment_specification(TACTILE).add_constraint("quantity", "tactile_pad", 2).add_constraint("capacity", "memory", 150)
robot.rules({GRASP: [FORCE, TACTILE], RELEASE: FORCE, MOVE_BASE: TACTILE})

scenario = Scenario(
    name="two_detectors",
    description="grasp selects the force and the tactile detector at once (Algorithm 1's early return)",
    model=robot.build(),
    initial=(LoadChange("arm_pc", 300), LoadChange("hand_pc", 100)),
    timeline=(TimedEvent(0.0, ActionChange(HOLD), "t0"), TimedEvent(2.0, ActionChange(GRASP), "t1")),
    checker=Bounds(
        actions=(HOLD, GRASP, MOVE_BASE, RELEASE),
        devices=("lwr_wrench", "pad_1"),
        platforms=("hand_pc",),
        start_failures=1,
        max_failures=2,
    ),
    expected={
        # desmon run (SimPy world), seed 0, per deployer: asserted exactly by tests/test_scenarios_sim.py
        # (the 2 s of hold have no rule: unmonitored whatever the deployer does)
        "desmon": {
            "violated": [], "errors": {}, "unmonitored_exposure_s": 2.5, "risky_time_s": 7.0,
            "unmonitored_by_cause_s": {"no_rule": 2.0, "not_deployed": 0.0, "starting": 0.5, "input_lost": 0.0, "cannot_detect": 0.0},
        },
        "paper": {
            "violated": ["coverage", "preferred-when-possible"], "errors": {}, "unmonitored_exposure_s": 7.0, "risky_time_s": 7.0,
            "unmonitored_by_cause_s": {"no_rule": 2.0, "not_deployed": 5.0, "starting": 0.0, "input_lost": 0.0, "cannot_detect": 0.0},
        },
        "verify": {
            # desmon verify --continue: verdict, distinct states, shortest counterexample lengths
            "desmon": {"verdict": "HOLDS", "states": 40, "counterexamples": {}},
            "paper": {"verdict": "VIOLATED", "states": 52, "counterexamples": {"coverage": 1, "errors-justified": 2, "preferred-when-possible": 1}},
        },
    },
)

if __name__ == "__main__":
    from desmon.verify.report import run_script

    raise SystemExit(run_script(scenario))
