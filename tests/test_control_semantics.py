"""One Control semantics: every engine refuses and allows exactly the same starts and stops.

The rules live in :mod:`desmon.deployment.control`; the checker's state store, the
repository replays and the SimPy infrastructure all execute Start/Stop through them.
"""

from __future__ import annotations

import hypothesis.strategies as st
from hypothesis import HealthCheck, given, settings

from desmon.verify.state import StoreInsert
from desmon.deployment.control import PLATFORM_DOWN, repository_control
from desmon.model.dsl import RobotBuilder
from desmon.model.events import ActionChange, DeviceFail, DeviceRepair, PlatformDown, PlatformUp
from desmon.model.scenario import Scenario, TimedEvent
from desmon.repository.facts import RepositoryInsert, load_model
from desmon.repository.query import RepositoryQuery
from desmon.repository.store import Repository
from desmon.sim.engine import SimWorld, simulate
from desmon.sim.processes import fault
from desmon.sim.world import Step, World
from desmon.verify.checker import Checker
from desmon.verify.replay import RepositoryRun
from desmon.verify.state import StateStore

GRAPHS = ("force", "tactile", "combined")
PLATFORMS = ("arm_pc", "hand_pc", "torso_pc")
DEVICES = ("wrench", "pad_1", "pad_2")


def _model():  # type: ignore[no-untyped-def]
    robot = RobotBuilder("r")
    robot.platform("arm_pc", memory=500).device("wrench", kind="force_sensor")
    robot.platform("hand_pc", memory=500).devices(["pad_1", "pad_2"], kind="tactile_pad")
    robot.platform("torso_pc", memory=1000)
    with robot.rpsl.perception_graph("force") as g:
        g.sensor("w", reads="force_sensor")
    with robot.rpsl.perception_graph("tactile") as g:
        g.sensor("t", reads="tactile_pad")
    with robot.rpsl.perception_graph("combined") as g:
        g.sensor("w", reads="force_sensor")
        g.sensor("t", reads="tactile_pad")
        g.processing("fuse", inputs=["w", "t"])
    for name in GRAPHS:
        spec = robot.depsl.deployment_specification(name).add_constraint("capacity", "memory", 10)
        if name == "tactile":
            spec.add_constraint("quantity", "tactile_pad", 2)
    return robot.build()


MODEL = _model()
SCENARIO = Scenario(
    name="control", model=MODEL, world=World(task=(Step("idle", 10_000.0),), horizon=10_000.0, signals=False)
)


class _Engines:
    """The same model under the three Control implementations, fed the same operations."""

    def __init__(self) -> None:
        self.store = StateStore(MODEL)
        self.store.begin()
        self.repo = Repository()
        load_model(self.repo, MODEL)
        self.insert = RepositoryInsert(self.repo, MODEL.robot)
        self.control = repository_control(self.repo, MODEL)
        self.sim = SimWorld(SCENARIO, seed=0)

    def fact(self, ev: object) -> None:
        if isinstance(ev, (DeviceFail, DeviceRepair)):
            working = isinstance(ev, DeviceRepair)
            StoreInsert(self.store).set_device_working(ev.device, working)
            self.insert.set_device_working(ev.device, working)
        else:
            up = isinstance(ev, PlatformUp)
            StoreInsert(self.store).set_platform_up(ev.platform, up)  # type: ignore[union-attr]
            self.insert.set_platform_up(ev.platform, up)  # type: ignore[union-attr]
        fault(self.sim.parts, ev, "test")  # type: ignore[arg-type]
        self.sim.env.run(until=self.sim.env.now + 1)  # the monitor notices it

    def start(self, graph: str, platform: str) -> tuple[bool, bool, bool]:
        proc = self.sim.env.process(self.sim.infra.start(graph, platform))
        self.sim.env.run(until=proc)
        return self.store.start(graph, platform), self.control.start(graph, platform), proc.value is True

    def stop(self, graph: str, platform: str) -> tuple[bool, bool, bool]:
        return self.store.stop(graph, platform), self.control.stop(graph, platform), self.sim.infra.stop(graph, platform)

    def deployments(self) -> tuple[tuple[str, str], ...]:
        a = self.store.deployments()
        b = RepositoryQuery(self.repo).deployments()
        c = RepositoryQuery(self.sim.repo).deployments()
        assert a == b == c == tuple(sorted(self.sim.instances))
        return a


def test_a_start_on_a_down_platform_is_refused_by_every_engine() -> None:
    e = _Engines()
    e.fact(PlatformDown("torso_pc"))
    assert e.start("combined", "torso_pc") == (False, False, False)
    assert e.store.refused == e.control.refused == PLATFORM_DOWN
    assert e.deployments() == ()


def test_a_start_whose_only_input_device_failed_is_refused_by_every_engine() -> None:
    e = _Engines()
    e.fact(DeviceFail("wrench"))
    assert e.start("combined", "torso_pc") == (False, False, False)
    assert e.store.refused == "reads force_sensor: wrench on arm_pc failed"
    assert e.start("tactile", "hand_pc") == (True, True, True)


def test_a_device_on_a_down_platform_cannot_feed_a_detector_elsewhere() -> None:
    e = _Engines()
    e.fact(PlatformDown("arm_pc"))
    assert e.start("combined", "torso_pc") == (False, False, False)
    e.fact(PlatformUp("arm_pc"))
    assert e.start("combined", "torso_pc") == (True, True, True)
    assert e.deployments() == (("combined", "torso_pc"),)


def test_one_readable_device_of_a_kind_is_enough_to_read_it() -> None:
    e = _Engines()
    e.fact(DeviceFail("pad_1"))
    assert e.start("combined", "torso_pc") == (True, True, True)


def test_a_start_on_a_platform_whose_devices_no_longer_meet_the_spec_is_refused() -> None:
    e = _Engines()
    e.fact(DeviceFail("pad_1"))  # tactile needs Quantity(tactile_pad >= 2): one pad is left
    assert e.start("tactile", "hand_pc") == (False, False, False)
    assert e.store.refused == e.control.refused == "the devices of hand_pc no longer meet Quantity(tactile_pad >= 2)"


def test_restarting_a_running_instance_is_a_no_op_success_and_stopping_a_missing_one_fails() -> None:
    e = _Engines()
    assert e.start("force", "arm_pc") == (True, True, True)
    e.fact(DeviceFail("wrench"))
    assert e.start("force", "arm_pc") == (True, True, True)  # already runs: nothing to refuse
    assert e.stop("force", "arm_pc") == (True, True, True)
    assert e.stop("force", "arm_pc") == (False, False, False)
    assert e.deployments() == ()


def test_a_stop_on_a_down_platform_succeeds_in_every_engine() -> None:
    e = _Engines()
    e.start("tactile", "hand_pc")
    e.fact(PlatformDown("hand_pc"))
    assert e.stop("tactile", "hand_pc") == (True, True, True)


_facts = st.one_of(
    st.builds(DeviceFail, st.sampled_from(DEVICES)),
    st.builds(DeviceRepair, st.sampled_from(DEVICES)),
    st.builds(PlatformDown, st.sampled_from(PLATFORMS)),
    st.builds(PlatformUp, st.sampled_from(PLATFORMS)),
)
_commands = st.tuples(st.sampled_from(("start", "stop")), st.sampled_from(GRAPHS), st.sampled_from(PLATFORMS))


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.one_of(_facts, _commands), max_size=25))
def test_generated_sequences_give_the_same_outcomes_and_deployed_on_edges_in_every_engine(ops: list) -> None:
    e = _Engines()
    for op in ops:
        if isinstance(op, tuple):
            verb, graph, platform = op
            outcomes = e.start(graph, platform) if verb == "start" else e.stop(graph, platform)
            assert len(set(outcomes)) == 1, f"{verb} {graph} on {platform}: store/replay/sim = {outcomes}"
        else:
            e.fact(op)
        e.deployments()


def _fixed_scenario() -> Scenario:
    robot = RobotBuilder("r")
    robot.platform("arm_pc", memory=500).device("wrench", kind="force_sensor")
    robot.platform("torso_pc", memory=1000)
    with robot.rpsl.perception_graph("force") as g:
        g.sensor("w", reads="force_sensor")
    robot.depsl.deployment_specification("force").executable_on("arm_pc")
    robot.rules({"grasp": "force"})
    world = World(
        task=(Step("idle", 2.0), Step("grasp", 5.0)), horizon=7.0, signals=False,
        faults=(TimedEvent(1.0, PlatformDown("arm_pc")),),
    )
    from desmon.verify.bounds import Bounds

    return Scenario(name="fixed-down", model=robot.build(), world=world,
                    checker=Bounds(actions=("idle", "grasp"), initial_action="idle", platforms=("arm_pc",)))


def test_the_papers_blind_fixed_start_on_a_down_platform_fails_in_the_sim_and_the_checker_alike() -> None:
    """End to end: the paper's Algorithm 1 starts a fixed deployment without any check;
    with its platform down, the SimPy world, the checker's store and the repository
    replay all refuse that start, and nothing is DEPLOYED_ON."""
    sc = _fixed_scenario()
    sim = simulate(sc, "paper")
    assert [(d["command"], d["ok"], d.get("why")) for d in sim.decisions] == [("start", False, PLATFORM_DOWN)]
    assert RepositoryQuery(sim.repo).deployments() == ()
    run = RepositoryRun(sc, "paper")
    run.step(PlatformDown("arm_pc"))
    log = run.step(ActionChange("grasp"))[1]
    assert [(str(c), ok) for c, ok in log.decisions] == [("start force on arm_pc", False)]
    ch = Checker(sc, "paper")
    key = ch.run_one(ch.initial(), PlatformDown("arm_pc"), ())[0]
    nkey, outcomes, slog, _ = ch.run_one(key, ActionChange("grasp"), ())
    assert [(str(c), ok) for c, ok in slog.decisions] == [("start force on arm_pc", False)]
    assert outcomes == ()  # a refused start is no choice point of the search
    assert nkey.deployments == run.query.deployments() == ()
