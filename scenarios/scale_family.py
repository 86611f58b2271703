"""A family of deployment models with a size parameter: N platforms, for the checker at scale.

Each of the ``platforms`` (N) PCs has 512 MB, a background load that moves in 150 MB
steps between 0 and 300 MB, may go down and come up, and has its own failing device: a
wrench on the even ones, one of a pair of tactile pads on the odd ones (each fails and
is repaired). Three detectors watch the robot's actions, each slot with a fallback
(hold and grasp prefer the combined detector over the force one, move_base the tactile
over the force one, release the force over the tactile one); the combined detector
reads a wrench and a pad. One start may fail per reaction. Each platform multiplies the
states by about 13 (``desmon verify scenarios/scale_family.py -p platforms=N`` finds
132,810 states for N = 4, 1,749,216 for 5, 22,114,758 for 6).

    desmon verify scenarios/scale_family.py -p platforms=4 --stats
    python -m bench.bench_scale --max-platforms 6      # states, seconds and bytes/state per N

``stochastic=True`` adds the world ``desmon analyze`` solves (the chain at scale): the
task repeats (grasp 2 s, hold 8 s, carry 20 s, release 2 s), every platform goes down
(MTTF 1 h, MTTR 60 s) and every failing device breaks (MTTF 30 min, MTTR 120 s) at
random, each load walks over its three levels (a step every 10 min on average), and 2 %
of the starts fail:

    desmon analyze scenarios/scale_family.py -p platforms=2 -p stochastic=True

Parameters: ``platforms`` (N, 2 to 12; 2 unless set, so that the tests running every
shipped scenario stay quick), ``stochastic`` (False), ``hours`` (the stochastic world's
horizon, 1). Figures: docs/findings.md ("The checker at scale").
"""

from __future__ import annotations

from desmon.errors import ScenarioError
from desmon.model import GRASP, HOLD, MOVE_BASE, RELEASE, RobotBuilder
from desmon.model.events import ActionChange, LoadChange
from desmon.model.params import parameters
from desmon.model.scenario import Scenario, TimedEvent
from desmon.sim.world import MTTF, LoadSteps, StartFailure, Step, World
from desmon.verify.bounds import Bounds, levels

p = parameters(platforms=2, stochastic=False, hours=1.0)
if not isinstance(p.platforms, int) or not 2 <= p.platforms <= 12:
    raise ScenarioError(f"platforms = {p.platforms!r}: give a whole number of platforms in [2, 12]")

PLATFORMS = tuple(f"pc{i}" for i in range(p.platforms))
#: each slot's detectors, preferred first
SLOTS = {HOLD: ("combined", "force"), GRASP: ("combined", "force"), MOVE_BASE: ("tactile", "force"), RELEASE: ("force", "tactile")}

robot = RobotBuilder("scale")
failing = []
for i, name in enumerate(PLATFORMS):
    pc = robot.platform(name, memory=512)
    if i % 2 == 0:
        pc.device(f"wrench{i}", kind="force_sensor")
        failing.append(f"wrench{i}")
    else:
        pc.devices([f"pad{i}a", f"pad{i}b"], kind="tactile_pad")
        failing.append(f"pad{i}a")
for graph, kinds in (("force", ("force_sensor",)), ("tactile", ("tactile_pad",)), ("combined", ("force_sensor", "tactile_pad"))):
    with robot.rpsl.perception_graph(graph) as g:
        for j, kind in enumerate(kinds):
            g.sensor(f"s{j}", reads=kind)
        g.processing("detect", inputs=[f"s{j}" for j in range(len(kinds))])
robot.depsl.deployment_specification("force").add_constraint("attribute", "platform_has", "force_sensor").add_constraint("capacity", "memory", 100)
robot.depsl.deployment_specification("tactile").add_constraint("quantity", "tactile_pad", 2).add_constraint("capacity", "memory", 150)
robot.depsl.deployment_specification("combined").add_constraint("capacity", "memory", 250)
robot.rules({action: [alternatives] for action, alternatives in SLOTS.items()})

#: the world of ``stochastic=True``: every fault the checker bounds allow, at a rate
STOCHASTIC = World(
    task=(Step(GRASP, 2.0), Step(HOLD, 8.0), Step(MOVE_BASE, 20.0), Step(RELEASE, 2.0)),
    repeat=True,
    horizon=3600.0 * p.hours,
    slip_rate=1.0 / 600.0,
    stochastic_faults=tuple(MTTF(name, mttf=3600.0, mttr=60.0) for name in PLATFORMS) + tuple(MTTF(d, mttf=1800.0, mttr=120.0) for d in failing),
    load_steps=tuple(LoadSteps(name, levels=(0, 150, 300), start=0, mean_interval=600.0) for name in PLATFORMS),
    start_failure=StartFailure(probability=0.02),
    start_latency=0.5,
    recognition_delay=0.2,
    heartbeat_timeout=1.0,
)

scenario = Scenario(
    name=f"scale_family_{p.platforms}p",
    description=f"{p.platforms} loaded platforms with failing devices, three detectors with fallbacks",
    model=robot.build(),
    initial=tuple(LoadChange(name, 0) for name in PLATFORMS),
    timeline=(TimedEvent(0.0, ActionChange(HOLD), "t0"),),
    world=STOCHASTIC if p.stochastic else None,
    checker=Bounds(
        actions=(HOLD, GRASP, MOVE_BASE, RELEASE),
        devices=tuple(failing),
        platforms=PLATFORMS,
        loads={name: levels(0, 300, 150) for name in PLATFORMS},
        start_failures=1,
    ),
)

if __name__ == "__main__":
    import sys

    from desmon.verify.checker import Checker
    from desmon.verify.report import format_result

    result = Checker(scenario, "desmon").run()
    print(format_result(result), end="")
    sys.exit(result.exit_code)
