"""A home-made test scenario for the timeline: what a user's own robot looks like.

Three actions of its own (``pour`` and ``inspect`` risky, ``wipe`` not), a GPU box that
declares ``gpu_memory`` besides memory, a spill detector reading a camera (no signal
model: it runs but can never alarm), and dozens of scripted faults, many of them
within a second of each other. tests/test_timeline_any_scenario.py draws it.
"""

from desmon.model import RobotBuilder
from desmon.model.events import ActionChange, DeviceFail, DeviceRepair, LoadChange, PlatformDown, PlatformUp
from desmon.model.scenario import Scenario, TimedEvent
from desmon.sim.world import Step, World

robot = RobotBuilder("busy-robot")
(robot.platform("onboard_pc", memory=2048)
    .device("wrist_ft", kind="force_sensor")
    .device("head_cam", kind="rgbd_camera"))
robot.platform("gpu_box", capacities={"memory": 4096, "gpu_memory": 8192})
robot.action("pour", risky=True, like="hold")
robot.action("inspect", risky=True, like="hold")
robot.action("wipe", risky=False, like="idle")

with robot.rpsl.perception_graph("force_slip_detector") as g:
    g.sensor("wrench", reads="force_sensor")
    g.processing("force_threshold", inputs=["wrench"])
with robot.rpsl.perception_graph("spill_detector") as g:
    g.sensor("images", reads="rgbd_camera")
    g.processing("segment_liquid", inputs=["images"])

(robot.depsl.deployment_specification("force_slip_detector")
    .add_constraint("attribute", "platform_has", "force_sensor")
    .add_constraint("capacity", "memory", 100))
(robot.depsl.deployment_specification("spill_detector")
    .add_constraint("capacity", "memory", 1500)
    .add_constraint("capacity", "gpu_memory", 3000))

robot.rules({
    "grasp": "force_slip_detector",
    "hold": "force_slip_detector",
    "pour": ["force_slip_detector", "spill_detector"],
    "inspect": "spill_detector",
    "wipe": "spill_detector",
})

#: 42 faults: the wrench and the camera fail and are repaired, the GPU box crashes and reboots
FAULTS = tuple(sorted(
    [
        TimedEvent(t, ev)
        for i in range(10)
        for t, ev in (
            (20.0 + 30.0 * i, DeviceFail("wrist_ft")),
            (20.4 + 30.0 * i, DeviceFail("head_cam")),
            (24.0 + 30.0 * i, DeviceRepair("wrist_ft")),
            (24.3 + 30.0 * i, DeviceRepair("head_cam")),
        )
    ] + [TimedEvent(100.0, PlatformDown("gpu_box")), TimedEvent(130.0, PlatformUp("gpu_box"))],
    key=lambda te: te.time,
))

scenario = Scenario(
    name="busy_robot",
    description="a home-made robot: its own actions, a GPU box, a camera without a signal model, 42 faults",
    model=robot.build(),
    initial=(LoadChange("onboard_pc", 500), LoadChange("gpu_box", 1000, "gpu_memory")),
    timeline=(TimedEvent(0.0, ActionChange("grasp"), "t0"),),
    world=World(
        task=(Step("grasp", 3.0), Step("hold", 5.0), Step("pour", 12.0), Step("inspect", 6.0), Step("wipe", 14.0)),
        repeat=True,
        horizon=320.0,
        faults=FAULTS,
        start_latency=0.3,
        signals=True,
    ),
)
