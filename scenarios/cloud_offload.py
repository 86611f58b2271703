"""Cloud offload: the Care-O-bot leases an edge server when its own PCs are full.

The coffee robot of the case study (hand_pc 320 MB: the combined detector fits only on
torso_pc) gets a busy torso: its background load random-walks up to 900 MB, and above
774 MB the combined detector (250 MB) has no home on board. An edge server can be
leased on demand: it joins 20 s after it is requested, has 2 GB, and is reached over
a network link of 8 ms. Latency limits say which detectors may run remotely: the force
and combined detectors tolerate 10 ms, the tactile detector (it runs on the pads'
1 kHz stream) only 2 ms, so it never leaves the robot.

Preferences: the combined detector prefers a platform on board (attribute
``onboard=yes``, weight 1) and the most free memory (weight 0.5); it moves back on
board only when the gain exceeds 0.6 (rebalancing with hysteresis), after which the
idle edge server is released (it leaves after 120 s without a detector).

The robot changes speed now and then (every 15 min on average): at high speed the
combined detector asks for 350 MB instead of 250 MB (a ``RequirementChange`` the
deployer re-checks like any fact).

Parameters: ``lease`` (lease the edge server when nothing fits, default True),
``hours`` (length of the shift, default 2), ``stochastic`` (default False): True gives
every event the checker explores a rate, for ``desmon analyze``: the torso load steps
between the checker's two levels (600 and 800 MB, on average every 5 min) instead of
the Gaussian walk, and the wrench breaks down (MTTF 1 h, MTTR 5 min).

    desmon replay scenarios/cloud_offload.py              # the scripted walk-through, step by step
    desmon explain scenarios/cloud_offload.py combined_slip_detector --at leased
    desmon run scenarios/cloud_offload.py                 # with the lease
    desmon run scenarios/cloud_offload.py -p lease=False  # without: exposure rises
    desmon verify scenarios/cloud_offload.py              # joins and leaves in every order: HOLDS
    desmon analyze scenarios/cloud_offload.py -p stochastic=True   # the exact unmonitored time, with the lease
"""

from __future__ import annotations

from desmon.model import GRASP, HOLD, IDLE, MOVE_BASE, RELEASE
from desmon.model.cob3 import COMBINED, FORCE, LOADS, PADS, TACTILE, care_o_bot
from desmon.model.events import ActionChange, LoadChange, PlatformJoin, PlatformLeave, RequirementChange
from desmon.model.requirements import Capacity
from desmon.model.params import parameters
from desmon.model.scenario import Scenario, TimedEvent
from desmon.sim.world import MTTF, Lease, LoadSteps, LoadWalk, RandomChanges, Step, World
from desmon.verify.bounds import Bounds, levels

p = parameters(lease=True, hours=2.0, stochastic=False)

#: The robot speeds up: the combined detector samples faster and needs 350 MB; and back.
FAST = RequirementChange(COMBINED, add=(Capacity("memory", 350),), remove=(Capacity("memory", 250),), label="fast: 350 MB")
SLOW = RequirementChange(COMBINED, add=(Capacity("memory", 250),), remove=(Capacity("memory", 350),), label="slow: 250 MB")

robot = care_o_bot(specs=False, attributes={"onboard": "yes"})
robot.platform(
    "edge", memory=2048, attributes={"os": "linux", "arch": "x86_64", "onboard": "no"},
    properties={"link_latency_ms": 8.0}, on_demand=True, startup_s=20.0,
)
(robot.depsl.deployment_specification(FORCE)
    .add_constraint("attribute", "platform_has", "force_sensor").add_constraint("capacity", "memory", 50)
    .add_constraint("maximum", "link_latency_ms", 10))
(robot.depsl.deployment_specification(TACTILE)
    .add_constraint("quantity", "tactile_pad", len(PADS)).add_constraint("capacity", "memory", 150)
    .add_constraint("maximum", "link_latency_ms", 2))
(robot.depsl.deployment_specification(COMBINED)
    .add_constraint("capacity", "memory", 250).add_constraint("maximum", "link_latency_ms", 10)
    .prefer("attribute", "onboard", "yes", weight=1.0).prefer("most_free", "memory", weight=0.5)
    .rebalance(0.6))

scenario = Scenario(
    name="cloud_offload",
    description="the Care-O-bot leases an edge server when its own PCs are full",
    model=robot.build(),
    initial=tuple(LoadChange(pc, mb) for pc, mb in LOADS.items()),
    timeline=(  # desmon replay / explain: one grasp, the torso fills up, the edge server is leased, the torso empties
        TimedEvent(0.0, ActionChange(GRASP), "t0"),
        TimedEvent(5.0, LoadChange("torso_pc", 850), "full"),
        TimedEvent(25.0, PlatformJoin("edge"), "leased"),
        TimedEvent(60.0, LoadChange("torso_pc", 600), "room"),
        TimedEvent(90.0, FAST, "fast"),
        TimedEvent(200.0, PlatformLeave("edge"), "returned"),
    ),
    world=World(
        task=(Step(IDLE, 20.0), Step(GRASP, 2.0), Step(HOLD, 3.0), Step(MOVE_BASE, 30.0), Step(RELEASE, 2.0)),
        repeat=True,
        horizon=p.hours * 3600.0,
        slip_rate=1.0 / 600.0,
        start_latency=0.3,
        load_walks=() if p.stochastic else (LoadWalk("torso_pc", start=600, sigma=40.0, interval=30.0, low=400, high=900),),
        load_steps=(LoadSteps("torso_pc", levels=(600, 800), start=600, mean_interval=300.0),) if p.stochastic else (),
        stochastic_faults=(MTTF("lwr_wrench", mttf=3600.0, mttr=300.0),) if p.stochastic else (),
        recognition_delay=0.1,
        heartbeat_timeout=0.5,
        block=1.0,
        lease=Lease(idle_s=120.0) if p.lease else None,
        random_changes=RandomChanges(changes=(FAST, SLOW), mean_interval=900.0),
    ),
    checker=Bounds(  # desmon verify: the delivery task, the torso load, the edge server and the speed changes in every order
        task={IDLE: (GRASP,), GRASP: (HOLD,), HOLD: (MOVE_BASE, RELEASE), MOVE_BASE: (HOLD,), RELEASE: (IDLE,)},
        initial_action=IDLE,
        loads={"torso_pc": levels(600, 800, 200)},
        joins=("edge",),
        requirement_changes=(FAST, SLOW),
        devices=("lwr_wrench",),
        max_failures=1,
    ),
)
