"""Fallback detectors under memory pressure: errors that describe the present, and the
upgrade back to the preferred detector.

The Care-O-bot's selector has fallbacks: while grasping and holding it prefers the
combined detector (250 MB) and falls back to the force detector; on hand-over it
prefers the force detector and falls back to the tactile one. Here the force detector
(100 MB) may run on any PC (it reads the LWR's wrench over the network), so both
alternatives of the grasp slot compete for ``torso_pc``'s memory. Its background load
moves between 600 and 900 MB:

* at 800 MB the combined detector no longer fits: it is stopped with an error, and the
  force detector serves the slot on ``torso_pc``. The error for the combined detector
  clears at once: the slot is served, nothing is wrong with monitoring.
* back at 700 MB the combined detector would fit, but only if the force detector's
  100 MB were freed. The default upgrade policy (``break-before-make``) stops the force
  detector, starts the combined one, and falls back again if that start fails; the
  robot is blind from the stop until the combined detector is warm.
  ``--deployer desmon-keep-fallback`` keeps the force detector instead.
* a broken wrench makes the force detector unstartable on hand-over: the tactile
  fallback serves, and the force detector's error clears with it.

The deployer as it was before (``--deployer mutant:stale-errors`` in the tests: errors
stand per graph, no upgrade) keeps an error for the combined detector standing while the
force detector serves its slot; ``desmon verify`` finds it (invariant ``errors-current``).

Run: ``desmon run scenarios/fallbacks.py`` (an 8-hour day) and
``desmon verify scenarios/fallbacks.py``.
"""

from __future__ import annotations

from desmon.model import GRASP, HOLD, IDLE, MOVE_BASE, RELEASE
from desmon.model.cob3 import COMBINED, FORCE, LOADS, PADS, TACTILE, care_o_bot
from desmon.model.events import LoadChange
from desmon.model.scenario import Scenario
from desmon.sim.world import MTTF, LoadWalk, StartFailure, Step, World
from desmon.verify.bounds import Bounds, levels

robot = care_o_bot(specs=False, rules=False)
robot.depsl.deployment_specification(FORCE).add_constraint("capacity", "memory", 100)
robot.depsl.deployment_specification(TACTILE).add_constraint("quantity", "tactile_pad", len(PADS)).add_constraint(
    "capacity", "memory", 150
)
robot.depsl.deployment_specification(COMBINED).add_constraint("capacity", "memory", 250)
robot.rules({
    GRASP: [(COMBINED, FORCE)],
    HOLD: [(COMBINED, FORCE)],
    MOVE_BASE: TACTILE,
    RELEASE: [(FORCE, TACTILE)],
})

scenario = Scenario(
    name="fallbacks",
    description="fallback detectors competing for torso_pc's memory; errors describe the present; upgrades",
    model=robot.build(),
    initial=tuple(LoadChange(p, mb) for p, mb in LOADS.items()),
    world=World(
        task=(Step(IDLE, 20.0), Step(GRASP, 2.0), Step(HOLD, 3.0), Step(MOVE_BASE, 30.0), Step(RELEASE, 2.0)),
        repeat=True,
        horizon=8 * 3600.0,
        slip_rate=1.0 / 600.0,
        stochastic_faults=(MTTF("lwr_wrench", mttf=3600.0, mttr=120.0),),
        start_latency=0.3,
        platform_latency=(("torso_pc", 0.4), ("arm_pc", 0.25)),
        start_failure=StartFailure(probability=0.02),
        load_walks=(LoadWalk("torso_pc", start=600, sigma=60.0, interval=20.0, low=600, high=900),),
        recognition_delay=0.1,
        heartbeat_timeout=0.5,
        block=1.0,
    ),
    checker=Bounds(  # desmon verify: the delivery cycle, torso_pc's load in 100 MB steps, a wrench that breaks
        task={IDLE: (GRASP,), GRASP: (HOLD,), HOLD: (MOVE_BASE, RELEASE), MOVE_BASE: (HOLD,), RELEASE: (IDLE,)},
        initial_action=IDLE,
        devices=("lwr_wrench",),
        loads={"torso_pc": levels(600, 900, 100)},
        start_failures=1,
    ),
    expected={
        "verify": {
            # desmon verify --continue: verdict, distinct states, shortest counterexample lengths
            "desmon": {"verdict": "HOLDS", "states": 68, "counterexamples": {}},
            "paper": {"verdict": "VIOLATED", "states": 64, "counterexamples": {"valid-or-error": 2, "coverage": 2, "errors-justified": 2, "preferred-when-possible": 2}},
            "desmon-keep-fallback": {"verdict": "VIOLATED", "states": 68, "counterexamples": {"preferred-when-possible": 2}},
        },
        # desmon run --until 7200 --seed 0, per deployer (tests/test_scenarios_sim.py)
        "first_2_h": {
            "desmon": {
                "switches": 378, "upgrades": 4, "upgrades_failed": 0, "upgrade_blind_s": 3.6,
                "errors": {"deployment_failed": 6, "no_acceptable_platforms": 111},
                "unmonitored_exposure_s": 306.619351, "violations": 0,
            },
            "desmon-keep-fallback": {
                "switches": 378, "upgrades": 0, "upgrades_failed": 0, "upgrade_blind_s": 0.0,
                # preferred-when-possible: it never upgrades, also where an action change makes it due
                "errors": {"deployment_failed": 6, "no_acceptable_platforms": 116},
                "unmonitored_exposure_s": 289.469351, "violations": 5,
            },
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
