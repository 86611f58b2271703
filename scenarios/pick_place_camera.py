"""A robot of a user's own: three computers, a wrist force/torque sensor and a camera,
picking, carrying and placing parts all shift long.

Not the paper's Care-O-bot: a smaller arm on a mobile base, written with the builder
DSL as a user would write theirs (docs/scenarios.md). Its actions are its own
(``pick`` like ``grasp``, ``carry`` like ``move_base``, ``place`` like ``release``,
``inspect`` like ``hold``); ``wrist_ft`` on ``wrist_pc`` feeds a force slip detector,
``cam`` on ``vision_pc`` a camera slip detector for which desmon has no signal model
(it runs and uses memory but cannot detect a slip, so it never counts as watching).
The rules want the force detector in ``pick``, ``carry`` and ``place`` (the camera
detector as the fallback in ``carry``) and nothing in ``inspect``, a risky action no
rule covers: ``run``, ``verify`` and ``analyze`` warn about it, and its seconds count as
unmonitored.

Every fault the checker bounds allow has a rate in the World, so ``desmon analyze``
solves it exactly:

    desmon analyze scenarios/pick_place_camera.py
    desmon run scenarios/pick_place_camera.py

Parameters (``-p NAME=VALUE``): ``hours`` (default 8), ``inspect_rule`` (False: no rule
for ``inspect``; True: the force detector watches it too), ``camera_rate`` (0: the camera
detector cannot detect; a probability above 0: the rate at which it catches a slip it
watches, given in ``World.detection_rates`` as a user would from their own trials).
"""

from __future__ import annotations

from desmon.model.dsl import RobotBuilder
from desmon.model.events import LoadChange
from desmon.model.params import parameters
from desmon.model.scenario import Scenario
from desmon.sim.world import MTTF, StartFailure, Step, World
from desmon.verify.bounds import Bounds

p = parameters(hours=8.0, inspect_rule=False, camera_rate=0.0)

robot = RobotBuilder("pick_place_arm")
robot.platform("base_pc", memory=1024, attributes={"os": "linux", "arch": "x86_64"})
robot.platform("wrist_pc", memory=256, attributes={"os": "linux", "arch": "armv7"}).device(
    "wrist_ft", kind="force_sensor", vendor="ati", version="mini45"
)
robot.platform("vision_pc", memory=2048, attributes={"os": "linux", "arch": "x86_64"}).device(
    "cam", kind="camera", vendor="basler", version="ace2"
)

with robot.rpsl.perception_graph("force_slip_detector") as g:
    g.sensor("wrench", reads="force_sensor")
    g.processing("tare", inputs=["wrench"])
    g.processing("threshold", inputs=["tare"])
with robot.rpsl.perception_graph("camera_slip_detector") as g:
    g.sensor("image", reads="camera")
    g.processing("optical_flow", inputs=["image"])
    g.processing("classify", inputs=["optical_flow"])

robot.depsl.deployment_specification("force_slip_detector").add_constraint("capacity", "memory", 200).add_constraint(
    "attribute", "os", "linux"
)
robot.depsl.deployment_specification("camera_slip_detector").add_constraint("capacity", "memory", 600)

robot.action("pick", like="grasp")
robot.action("carry", like="move_base")
robot.action("place", like="release")
robot.action("inspect", like="hold")
rules: dict[str, object] = {
    "pick": "force_slip_detector",
    "carry": [("force_slip_detector", "camera_slip_detector")],
    "place": "force_slip_detector",
}
if p.inspect_rule:
    rules["inspect"] = "force_slip_detector"
robot.rules(rules)

scenario = Scenario(
    name="pick_place_camera",
    description="a user's pick-and-place robot: wrist F/T sensor, a camera without a signal model, an action no rule covers",
    model=robot.build(),
    initial=(LoadChange("base_pc", 300), LoadChange("wrist_pc", 20), LoadChange("vision_pc", 900)),
    world=World(
        task=(Step("idle", 15.0), Step("pick", 3.0), Step("inspect", 4.0), Step("carry", 20.0), Step("place", 3.0)),
        repeat=True,
        horizon=p.hours * 3600.0,
        slip_rate=1.0 / 300.0,
        stochastic_faults=(MTTF("wrist_ft", mttf=1800.0, mttr=240.0), MTTF("wrist_pc", mttf=7200.0, mttr=120.0)),
        start_latency=0.5,
        platform_latency=(("vision_pc", 1.5),),
        start_failure=StartFailure(probability=0.02),
        recognition_delay=0.2,
        heartbeat_timeout=1.0,
        detection_rates={"camera_slip_detector": p.camera_rate} if p.camera_rate else {},
    ),
    checker=Bounds(
        task={"idle": ("pick",), "pick": ("inspect",), "inspect": ("carry",), "carry": ("place",), "place": ("idle",)},
        initial_action="idle",
        devices=("wrist_ft",),
        platforms=("wrist_pc",),
        start_failures=1,
        max_failures=2,
    ),
)
