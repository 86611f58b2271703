"""A fleet: 100 Care-O-bots doing coffee deliveries, sharing 20 edge servers.

Each robot (``r000`` ... ``r099``) is the case study's Care-O-bot with its own PCs and
sensors (``r017.torso_pc``, ``r017.lwr_wrench``, ...), its own context monitor,
selector and deployer, and the robot day's task, faults, start failures and load walks
(its random draws from a seed derived from the run's ``--seed`` and its name). The
robots' idle waits differ (15-25 s), so their grasps are not in lock step. The torso
load walks up to 900 MB: above 774 MB the combined detector (250 MB) has no home on
board and goes to an edge server.

The 20 edge servers (``edge00`` ...) have 1 GB each and are reached over links of 3 to
15 ms. Latency limits decide what may run there: the force and combined detectors
tolerate 10 ms, the tactile detector (1 kHz pads) 2 ms, so it never leaves its robot;
the force detector needs the wrench on its platform anyway. The combined detector
prefers its own robot (``onboard=yes``) and the most free memory; every detector is
restricted to its own robot's PCs or an edge server (``host=r017`` or ``host=edge``).

An edge server's memory is shared: one robot's detector there is capacity every other
robot's deployer sees.

    desmon run scenarios/fleet.py                                 # 100 robots, 20 edges, 8 h
    desmon run scenarios/fleet.py -p robots=10 -p hours=1         # a smaller fleet
    desmon verify scenarios/fleet.py -p robots=2 -p edges=1       # the checker: HOLDS

``desmon verify`` (and replay / explain / show) see ONE model of the whole fleet in
which all robots share one action context (the rule table maps one context to the
slots of every robot); the fleet run gives each robot its own. See docs/fleet.md.

Parameters: ``robots`` (default 100), ``edges`` (default 20), ``hours`` (default 8),
``edge_memory`` (MB per edge server, default 1024), ``admission`` (the edge servers'
admission control, default True; ``-p admission=False`` shows concurrent starts of
different robots over-committing an edge server, which the audit reports).
"""

from __future__ import annotations

from desmon.errors import ScenarioError
from desmon.model import GRASP, HOLD, IDLE, MOVE_BASE, RELEASE, RobotBuilder
from desmon.model.cob3 import COMBINED, FORCE, LOADS, PADS, TACTILE, graphs
from desmon.model.events import LoadChange
from desmon.model.graph import SensorComponent
from desmon.model.params import parameters
from desmon.model.scenario import Scenario
from desmon.sim.fleet import Fleet, merged_model
from desmon.sim.world import MTTF, LoadWalk, StartFailure, Step, World
from desmon.verify.bounds import Bounds, levels

p = parameters(robots=100, edges=20, hours=8.0, edge_memory=1024.0, admission=True)

if not isinstance(p.robots, int) or not 1 <= p.robots <= 1000:
    raise ScenarioError(f"robots = {p.robots!r}: give a whole number of robots in [1, 1000]")
if not isinstance(p.edges, int) or not 1 <= p.edges <= 200:
    raise ScenarioError(f"edges = {p.edges!r}: give a whole number of edge servers in [1, 200] (the fleet shares edge servers)")
if not p.edge_memory > 0:
    raise ScenarioError(f"edge_memory = {p.edge_memory!r}: give a positive number of MB")

EDGE_MEMORY = p.edge_memory
#: link latency (ms) of edge server i: 3 to 15 ms, about 60 % of them within 10 ms
EDGE_LATENCY = tuple(3.0 + (i * 3.7) % 12.0 for i in range(p.edges))
EDGES = tuple(f"edge{i:02d}" for i in range(p.edges))


def robot_model(rid: str) -> RobotBuilder:
    """The Care-O-bot of the case study with names prefixed by ``rid``, plus the edges."""
    n = lambda s: f"{rid}.{s}"  # noqa: E731
    robot = RobotBuilder(rid)
    own = {"os": "linux", "onboard": "yes", "host": rid}
    robot.platform(n("torso_pc"), memory=1024, attributes={**own, "arch": "x86_64"}, properties={"link_latency_ms": 2.0})
    robot.platform(n("arm_pc"), memory=512, attributes={**own, "arch": "x86_64"}, properties={"link_latency_ms": 1.0}).device(
        n("lwr_wrench"), kind="force_sensor", vendor="kuka", version="lwr4"
    )
    robot.platform(n("hand_pc"), memory=320, attributes={**own, "arch": "armv7"}, properties={"link_latency_ms": 1.0}).devices(
        [n(f"pad_{x}") for x in PADS], kind="tactile_pad", vendor="weiss", version="dsa9205"
    )
    for name, latency in zip(EDGES, EDGE_LATENCY):
        robot.platform(
            name, memory=EDGE_MEMORY, attributes={"os": "linux", "arch": "x86_64", "onboard": "no", "host": "edge"},
            properties={"link_latency_ms": latency},
        )
    # the three graphs under this robot's names
    tmp = RobotBuilder("tmp")
    graphs(tmp)
    for g in tmp.build().graphs:
        with robot.rpsl.perception_graph(n(g.name)) as b:
            for c in g.components:
                if isinstance(c, SensorComponent):
                    b.sensor(c.name, reads=c.device_kind)
                else:
                    b.processing(c.name, inputs=list(c.inputs))
    mine = ("selection", f"host={rid}", "host=edge")
    (robot.depsl.deployment_specification(n(FORCE))
        .add_constraint("attribute", "platform_has", "force_sensor").add_constraint("capacity", "memory", 50)
        .add_constraint("maximum", "link_latency_ms", 10).add_constraint(*mine))
    (robot.depsl.deployment_specification(n(TACTILE))
        .add_constraint("quantity", "tactile_pad", len(PADS)).add_constraint("capacity", "memory", 150)
        .add_constraint("maximum", "link_latency_ms", 2).add_constraint(*mine))
    (robot.depsl.deployment_specification(n(COMBINED))
        .add_constraint("capacity", "memory", 250).add_constraint("maximum", "link_latency_ms", 10).add_constraint(*mine)
        .prefer("attribute", "onboard", "yes", weight=1.0).prefer("most_free", "memory", weight=0.5))
    robot.rules({GRASP: n(COMBINED), MOVE_BASE: n(TACTILE), RELEASE: n(FORCE)})
    return robot


def robot_scenario(i: int) -> Scenario:
    rid = f"r{i:03d}"
    n = lambda s: f"{rid}.{s}"  # noqa: E731
    return Scenario(
        name=rid,
        model=robot_model(rid).build(),
        initial=tuple(LoadChange(n(pc), mb) for pc, mb in LOADS.items()),
        world=World(
            task=(Step(IDLE, 15.0 + (i * 7) % 11), Step(GRASP, 2.0), Step(HOLD, 3.0), Step(MOVE_BASE, 30.0), Step(RELEASE, 2.0)),
            repeat=True,
            horizon=p.hours * 3600.0,
            slip_rate=1.0 / 600.0,
            stochastic_faults=(
                MTTF(n("lwr_wrench"), mttf=3600.0, mttr=120.0),
                MTTF(n("pad_thumb_prox"), mttf=7200.0, mttr=300.0),
                MTTF(n("hand_pc"), mttf=14400.0, mttr=60.0),
                MTTF(n("torso_pc"), mttf=28800.0, mttr=90.0),
            ),
            start_latency=0.3,
            platform_latency=((n("torso_pc"), 0.4), (n("arm_pc"), 0.25)),
            start_failure=StartFailure(probability=0.02),
            load_walks=(
                LoadWalk(n("torso_pc"), start=600, sigma=40.0, interval=30.0, low=400, high=900),
                LoadWalk(n("arm_pc"), start=300, sigma=15.0, interval=30.0, low=200, high=450),
            ),
            recognition_delay=0.1,
            heartbeat_timeout=0.5,
            block=1.0,
            signals=False,
        ),
    )


robots = tuple(robot_scenario(i) for i in range(p.robots))
fleet = Fleet(robots=robots, edges=EDGES, description="Care-O-bots sharing edge servers", admission=p.admission)

scenario = Scenario(
    name="fleet",
    description=f"{p.robots} Care-O-bots sharing {p.edges} edge servers",
    # what desmon verify / replay / explain see: the first two robots (all robots are built alike)
    # and the edge servers as ONE model, both robots in one shared context
    model=merged_model((r.model for r in robots[:2]), EDGES),
    initial=tuple(ev for r in robots[:2] for ev in r.initial),
    world=fleet,
    # desmon verify: both robots in the same context, their torsos filling up (the combined detectors
    # move to an edge server), wrenches failing, starts failing, in every order
    checker=Bounds(
        task={IDLE: (GRASP,), GRASP: (HOLD,), HOLD: (MOVE_BASE, RELEASE), MOVE_BASE: (HOLD,), RELEASE: (IDLE,)},
        initial_action=IDLE,
        loads={f"{r.model.robot}.torso_pc": levels(600, 800, 200) for r in robots[:2]},
        devices=tuple(f"{r.model.robot}.lwr_wrench" for r in robots[:2]),
        start_failures=1,
        max_failures=2,
    ),
)
