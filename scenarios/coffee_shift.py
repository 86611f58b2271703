"""The coffee robot's 8 h shift, in rates: the scenario ``desmon analyze`` answers exactly.

The paper's Care-O-bot (``coffee_handover``: combined detector for grasp, tactile for
move_base, force for release; hand_pc 320 MB, so the combined detector fits only on
torso_pc) delivers coffee all shift long: wait 20 s, grasp 2 s, hold 3 s, carry 30 s,
hand over 2 s, and again. Its parts break and are repaired at random (exponential
MTTF / MTTR): the arm's wrench estimate (the force sensor) every hour on average, a
tactile pad every 2 h, hand_pc every 4 h, torso_pc every 8 h. Starts take 0.25-0.4 s
and fail with probability 2 %; the context monitor recognises an action after 0.1 s
and notices a failure or repair after 0.5 s. Slips: one per 10 min of mug-in-hand time.

Every fault the checker bounds allow has a rate in the World, and every rate an event
in the bounds, so the chain of ``desmon analyze`` is the World's own process.

Parameters (``-p NAME=VALUE``): ``force_sensors`` (1, or 2: a wrist force/torque
sensor ``wrist_ft`` on a small ``wrist_pc`` backs up the arm's wrench estimate),
``wrench_mttf`` (s, default 3600), ``hours`` (default 8), ``faults`` (False: nothing
breaks; the exposure left is the blind time of the switches alone).

    desmon analyze scenarios/coffee_shift.py                      # exact exposure per hour and per shift
    desmon analyze scenarios/coffee_shift.py -p force_sensors=2   # what a second force sensor buys
    desmon run scenarios/coffee_shift.py --timing exponential --no-signals --seed 3   # the same world, simulated
"""

from __future__ import annotations

from desmon.model import GRASP, HOLD, IDLE, MOVE_BASE, RELEASE
from desmon.model.cob3 import LOADS, care_o_bot
from desmon.model.events import LoadChange
from desmon.model.params import parameters
from desmon.model.scenario import Scenario
from desmon.sim.world import MTTF, StartFailure, Step, World
from desmon.verify.bounds import Bounds

p = parameters(force_sensors=1, wrench_mttf=3600.0, hours=8.0, faults=True)
if p.force_sensors not in (1, 2):
    from desmon.errors import ScenarioError

    raise ScenarioError(f"coffee_shift: force_sensors = {p.force_sensors!r}: give 1 or 2")

robot = care_o_bot()
faults = [
    MTTF("lwr_wrench", mttf=p.wrench_mttf, mttr=120.0),
    MTTF("pad_thumb_prox", mttf=7200.0, mttr=300.0),
    MTTF("hand_pc", mttf=14400.0, mttr=60.0),
    MTTF("torso_pc", mttf=28800.0, mttr=90.0),
]
devices = ["lwr_wrench", "pad_thumb_prox"]
if not p.faults:
    faults, devices = [], []
if p.force_sensors == 2:
    robot.platform("wrist_pc", memory=128, attributes={"os": "linux", "arch": "armv7"}, properties={"link_latency_ms": 1.0}).device(
        "wrist_ft", kind="force_sensor", vendor="ati", version="mini45"
    )
    if p.faults:
        faults.append(MTTF("wrist_ft", mttf=p.wrench_mttf, mttr=120.0))
        devices.append("wrist_ft")

scenario = Scenario(
    name="coffee_shift",
    description="the coffee robot's shift of deliveries with random faults, in rates (desmon analyze)",
    model=robot.build(),
    initial=tuple(LoadChange(pc, mb) for pc, mb in LOADS.items()),
    world=World(
        task=(Step(IDLE, 20.0), Step(GRASP, 2.0), Step(HOLD, 3.0), Step(MOVE_BASE, 30.0), Step(RELEASE, 2.0)),
        repeat=True,
        horizon=p.hours * 3600.0,
        slip_rate=1.0 / 600.0,
        stochastic_faults=tuple(faults),
        start_latency=0.3,
        platform_latency=(("torso_pc", 0.4), ("arm_pc", 0.25)),
        start_failure=StartFailure(probability=0.02),
        recognition_delay=0.1,
        heartbeat_timeout=0.5,
    ),
    checker=Bounds(  # desmon verify: the shift's faults, at most two at once (desmon analyze drops that budget)
        task={IDLE: (GRASP,), GRASP: (HOLD,), HOLD: (MOVE_BASE,), MOVE_BASE: (RELEASE,), RELEASE: (IDLE,)},
        initial_action=IDLE,
        devices=tuple(devices),
        platforms=("torso_pc", "hand_pc") if p.faults else (),
        start_failures=1,
        max_failures=2,
    ),
)
