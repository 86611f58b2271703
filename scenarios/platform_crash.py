"""A platform crash while the combined detector runs.

The robot grasps the mug for a long time (grasp -> combined_slip_detector, 250 MB). The
combined detector starts on ``torso_pc`` (first acceptable platform); at t=8 s torso_pc
crashes, at t=15 s it reboots.

* ``desmon`` deployer: re-checks the deployment on the changed platform, stops the dead
  instance and migrates the detector to ``hand_pc`` (284 MB free); every audit holds.
* ``paper`` deployer (Algorithm 2 literally): starts a second instance on hand_pc and
  never stops the old one on torso_pc -> the audit reports ``single-instance`` (and
  ``desmon run --deployer paper`` exits 1).

Run: ``desmon run scenarios/platform_crash.py [--deployer paper]``.

Parameter ``stochastic`` (default False): True replaces the scripted crash by an hour of
grasp / carry / hand-over cycles in which torso_pc, hand_pc and the wrench break and
are repaired at random (MTTF / MTTR), the world ``desmon analyze`` solves exactly:
``desmon analyze scenarios/platform_crash.py -p stochastic=True``.
"""

from __future__ import annotations

from desmon.model import GRASP, MOVE_BASE, RELEASE
from desmon.model.events import LoadChange, PlatformDown, PlatformUp
from desmon.verify.bounds import Bounds, levels
from desmon.model.scenario import Scenario, TimedEvent
from desmon.model.cob3 import LOADS, care_o_bot
from desmon.model.params import parameters
from desmon.sim.world import MTTF, Slip, Step, World

p = parameters(stochastic=False)

#: the stochastic variant's world: every fault the checker bounds allow, at a rate
STOCHASTIC = World(
    task=(Step(GRASP, 25.0), Step(MOVE_BASE, 10.0), Step(RELEASE, 5.0)),
    repeat=True,
    horizon=3600.0,
    slip_rate=1.0 / 600.0,
    stochastic_faults=(MTTF("torso_pc", mttf=600.0, mttr=30.0), MTTF("hand_pc", mttf=1200.0, mttr=30.0), MTTF("lwr_wrench", mttf=1800.0, mttr=60.0)),
    start_latency=0.3,
    platform_latency=(("hand_pc", 0.4),),
    recognition_delay=0.1,
    heartbeat_timeout=0.5,
)

scenario = Scenario(
    name="platform_crash",
    description="torso_pc crashes while the combined slip detector runs on it",
    model=care_o_bot(hand_pc_memory=384).build(),  # hand_pc can host the combined detector too
    initial=tuple(LoadChange(p, mb) for p, mb in LOADS.items()),
    world=STOCHASTIC if p.stochastic else World(
        task=(Step(GRASP, 25.0),),
        horizon=25.0,
        faults=(TimedEvent(8.0, PlatformDown("torso_pc"), "crash"), TimedEvent(15.0, PlatformUp("torso_pc"), "reboot")),
        slips=(Slip(5.0, "down", "pulled"), Slip(20.0, "down", "pulled")),
        start_latency=0.3,
        platform_latency=(("hand_pc", 0.4),),
        recognition_delay=0.1,
        heartbeat_timeout=0.5,
    ),
    checker=Bounds(  # desmon verify: any crash/reboot of the two platforms that can host the combined detector
        actions=(GRASP, MOVE_BASE, RELEASE),
        devices=("lwr_wrench",),
        platforms=("torso_pc", "hand_pc"),
        start_failures=1,
        max_failures=2,
    ),
    expected={
        "verify": {
            # desmon verify --continue: verdict, distinct states, shortest counterexample lengths
            "desmon": {"verdict": "HOLDS", "states": 38, "counterexamples": {}},
            "paper": {"verdict": "VIOLATED", "states": 61, "counterexamples": {"valid-or-error": 2, "single-instance": 2, "coverage": 2, "errors-justified": 1, "preferred-when-possible": 3}},
        },
        # desmon run (SimPy world), seed 0, per deployer: asserted exactly by tests/test_scenarios_sim.py
        "desmon": {
            "violated": [],
            "errors": {},
            "placements": [("combined_slip_detector", "torso_pc"), ("combined_slip_detector", "hand_pc")],
            "migrations": 1,
            "slips_detected": 2,
        },
        "paper": {
            "violated": ["single-instance", "valid-or-error"],
            "errors": {},
            "placements": [("combined_slip_detector", "torso_pc"), ("combined_slip_detector", "hand_pc")],
        },
    },
)

if __name__ == "__main__":
    import sys

    from desmon.cli.run import format_summary
    from desmon.sim.engine import simulate

    r = simulate(scenario, sys.argv[1] if len(sys.argv) > 1 else "desmon")
    print(format_summary(r), end="")
    sys.exit(1 if r.violations else 0)
