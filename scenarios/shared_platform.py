"""Two deployments share a platform that changes (Algorithm 2's early return).

``main_pc`` (400 MB, the only platform with the ``gpu`` attribute both detectors need)
hosts ``vision_slip_detector`` (hold, move_base) and ``audio_slip_detector`` (move_base),
150 MB each; ``aux_pc`` cannot host either. When ``main_pc`` goes down, or its background
load leaves no room, the paper's Algorithm 2 handles the first active deployment
(error + stop, lines 8-10) and returns: the second keeps running on an invalid platform
and no error stands for it (``valid-or-error``). The ``desmon`` deployer re-checks both.

Run it: ``python scenarios/shared_platform.py [paper]``.
"""

from __future__ import annotations

from desmon.model import HOLD, IDLE, MOVE_BASE, RobotBuilder
from desmon.model.events import ActionChange
from desmon.model.scenario import Scenario, TimedEvent
from desmon.verify.bounds import Bounds, levels

VISION = "vision_slip_detector"
AUDIO = "audio_slip_detector"

robot = RobotBuilder("care-o-bot-3")
robot.platform("main_pc", memory=400, attributes={"gpu": "yes"}).device("camera", kind="camera").device("mic", kind="microphone")
robot.platform("aux_pc", memory=400, attributes={"gpu": "no"})

with robot.rpsl.perception_graph(VISION) as g:
    g.sensor("cam", reads="camera")
    g.processing("optical_flow", inputs=["cam"])
with robot.rpsl.perception_graph(AUDIO) as g:
    g.sensor("mic", reads="microphone")
    g.processing("friction_noise", inputs=["mic"])

robot.depsl.deployment_specification(VISION).add_constraint("attribute", "gpu", "yes").add_constraint("capacity", "memory", 150)
robot.depsl.deployment_specification(AUDIO).add_constraint("attribute", "gpu", "yes").add_constraint("capacity", "memory", 150)
robot.rules({HOLD: VISION, MOVE_BASE: [VISION, AUDIO]})

scenario = Scenario(
    name="shared_platform",
    description="two deployments share main_pc, which goes down or fills up (Algorithm 2's early return)",
    model=robot.build(),
    timeline=(TimedEvent(0.0, ActionChange(HOLD), "t0"), TimedEvent(1.0, ActionChange(MOVE_BASE), "t1")),
    checker=Bounds(
        actions=(IDLE, HOLD, MOVE_BASE),
        platforms=("main_pc",),
        loads={"main_pc": levels(0, 200, 100)},
        start_failures=1,
    ),
    expected={
        "verify": {
            # desmon verify --continue: verdict, distinct states, shortest counterexample lengths
            "desmon": {"verdict": "HOLDS", "states": 26, "counterexamples": {}},
            "paper": {"verdict": "VIOLATED", "states": 41, "counterexamples": {"valid-or-error": 2, "coverage": 1, "errors-justified": 1, "preferred-when-possible": 1}},
        },
    },
)

if __name__ == "__main__":
    from desmon.verify.report import run_script

    raise SystemExit(run_script(scenario))
