"""A kitchen robot pours coffee: the scenario that docs/scenarios.md builds step by step.

Two computers: ``onboard_pc`` (the robot's own PC, no GPU; the wrist force-torque
sensor and the head camera plug into it) and ``gpu_box`` (a GPU box on the robot's
network). Three safety monitors: a force slip detector (wrist F/T), a spill detector
that runs a network on the head camera's images and needs a GPU, and a lighter spill
detector for the CPU as its fallback. The robot's vocabulary adds two actions of its
own: ``pour`` (the cup is in the hand, tilted: its sensor signals are like ``hold``)
and ``wipe`` (the hand holds a cloth, not the cup: nothing can slip, like ``idle``).

Run it::

    desmon run docs/examples/kitchen_robot.py
    desmon run docs/examples/kitchen_robot.py -p signals=false
    desmon verify docs/examples/kitchen_robot.py
    desmon fuzz docs/examples/kitchen_robot.py --examples 50 --seed 1
"""

from __future__ import annotations

from desmon.model import RobotBuilder
from desmon.model.events import ActionChange, DeviceFail, DeviceRepair, LoadChange, PlatformDown, PlatformUp
from desmon.model.params import parameters
from desmon.model.scenario import Scenario, TimedEvent
from desmon.sim.world import MTTF, LoadWalk, Slip, StartFailure, Step, World
from desmon.verify.bounds import Bounds, levels

p = parameters(gpu_memory=4096, signals=True, ft_mttf=1800.0)

# --- 1. platforms and devices ---------------------------------------------------------
robot = RobotBuilder("kitchen-robot")
(robot.platform("onboard_pc", memory=2048, attributes={"gpu": "no", "os": "linux"})
    .device("wrist_ft", kind="force_sensor", vendor="ati", version="mini45")
    .device("head_cam", kind="rgbd_camera", vendor="intel", version="d435"))
robot.platform("gpu_box", memory=p.gpu_memory, attributes={"gpu": "yes", "os": "linux"}, preference=1.0)

# --- 2. the robot's own actions -------------------------------------------------------
robot.action("pour", risky=True, like="hold")    # cup in the hand, tilted
robot.action("wipe", risky=False, like="idle")   # a cloth in the hand: nothing to drop

# --- 3. perception graphs (RPSL) ------------------------------------------------------
with robot.rpsl.perception_graph("force_slip_detector") as g:
    g.sensor("wrench", reads="force_sensor")
    g.processing("tare", inputs=["wrench"])
    g.processing("force_threshold", inputs=["tare"])
with robot.rpsl.perception_graph("spill_detector") as g:
    g.sensor("images", reads="rgbd_camera")
    g.processing("segment_liquid", inputs=["images"])
    g.processing("spill_alarm", inputs=["segment_liquid"])
with robot.rpsl.perception_graph("spill_detector_cpu") as g:
    g.sensor("images", reads="rgbd_camera")
    g.processing("colour_blobs", inputs=["images"])
    g.processing("spill_alarm", inputs=["colour_blobs"])

# --- 4. deployment specifications (DepSL) ---------------------------------------------
(robot.depsl.deployment_specification("force_slip_detector")
    .add_constraint("attribute", "platform_has", "force_sensor")   # runs where the F/T sensor is
    .add_constraint("capacity", "memory", 100))
(robot.depsl.deployment_specification("spill_detector")
    .add_constraint("attribute", "gpu", "yes")                     # needs a GPU
    .add_constraint("capacity", "memory", 1500))
(robot.depsl.deployment_specification("spill_detector_cpu")
    .add_constraint("selection", "rgbd_camera", "gpu=yes")         # next to the camera, or on a GPU
    .add_constraint("capacity", "memory", 600))

# --- 5. rules: what each action wants ------------------------------------------------
robot.rules({
    "grasp": "force_slip_detector",
    "hold": "force_slip_detector",
    "move_base": "force_slip_detector",
    "pour": ["force_slip_detector", ("spill_detector", "spill_detector_cpu")],   # two slots, the 2nd with a fallback
    "release": "force_slip_detector",
    "wipe": [("spill_detector", "spill_detector_cpu")],
})

# --- 6. the scenario: what happens to the robot ---------------------------------------
scenario = Scenario(
    name="kitchen_robot",
    description="a kitchen robot pours coffee: GPU spill detector with a CPU fallback, force slip detector",
    model=robot.build(),
    initial=(LoadChange("onboard_pc", 900), LoadChange("gpu_box", 1000)),
    timeline=(  # desmon replay / explain / show: four moments, labelled
        TimedEvent(0.0, ActionChange("hold"), "t0"),
        TimedEvent(5.0, ActionChange("pour"), "t1"),
        TimedEvent(8.0, PlatformDown("gpu_box"), "t2"),
        TimedEvent(12.0, ActionChange("wipe"), "t3"),
    ),
    world=World(  # desmon run
        task=(
            Step("idle", 10.0), Step("grasp", 2.0), Step("hold", 3.0), Step("move_base", 20.0),
            Step("pour", 6.0), Step("hold", 2.0), Step("move_base", 20.0), Step("release", 2.0),
            Step("wipe", 15.0),
        ),
        repeat=True,
        horizon=3600.0,
        slips=(Slip(28.0, "down", "pulled"), Slip(37.0, "down", "pulled")),
        slip_rate=1.0 / 900.0,
        faults=(TimedEvent(600.0, PlatformDown("gpu_box")), TimedEvent(780.0, PlatformUp("gpu_box")),
                TimedEvent(1500.0, DeviceFail("head_cam")), TimedEvent(1620.0, DeviceRepair("head_cam"))),
        stochastic_faults=(MTTF("wrist_ft", mttf=p.ft_mttf, mttr=60.0),),
        start_latency=0.3,
        platform_latency={"gpu_box": 2.0},
        start_failure=StartFailure(probability=0.01),
        loads=(TimedEvent(1200.0, LoadChange("gpu_box", 3000)), TimedEvent(1800.0, LoadChange("gpu_box", 1000))),
        load_walks=(LoadWalk("onboard_pc", start=900, sigma=50.0, interval=30.0, low=600, high=1500),),
        recognition_delay=0.2,
        heartbeat_timeout=0.5,
        signals=p.signals,
        block=1.0,
    ),
    checker=Bounds(  # desmon verify / desmon fuzz
        task={
            "idle": ("grasp",), "grasp": ("hold",), "hold": ("move_base", "pour", "release"),
            "move_base": ("hold",), "pour": ("hold",), "release": ("wipe",), "wipe": ("idle",),
        },
        initial_action="idle",
        devices=("wrist_ft", "head_cam"),
        platforms=("gpu_box",),
        loads={"onboard_pc": levels(900, 1500, 300)},
        start_failures=1,
        max_failures=2,
    ),
    expected={  # pinned results (tests/test_scenarios_doc.py asserts them)
        "verify": {  # desmon verify --continue: verdict, distinct states, shortest counterexample lengths
            "desmon": {"verdict": "HOLDS", "states": 235, "counterexamples": {}},
            "paper": {
                "verdict": "VIOLATED", "states": 270,
                "counterexamples": {"valid-or-error": 4, "coverage": 3, "errors-justified": 2, "preferred-when-possible": 2},
            },
        },
        # desmon run, seed 0, default parameters
        "run": {"unmonitored_exposure_s": 339.0, "switches": 135, "slips_detected": 4, "false_alarms": 165, "violations": 0},
    },
)
