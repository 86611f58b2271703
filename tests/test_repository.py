"""Specification of the repository: Insert, Query, Notify, change log, snapshots, exports."""

import json

import networkx as nx
import pytest

from desmon.errors import QueryError
from desmon.model import RobotBuilder
from desmon.repository import (
    ImmediateControl,
    Repository,
    RepositoryQuery,
    graph_to_graphml,
    graph_to_json,
    labels as L,
    load_model,
    set_context,
    set_device_working,
    set_load,
    set_platform_up,
)


@pytest.fixture
def world():
    robot = RobotBuilder("r")
    robot.platform("pc1", memory=512).device("ft", kind="force_sensor")
    robot.platform("pc2", memory=256)
    with robot.rpsl.perception_graph("force") as g:
        g.sensor("w", reads="force_sensor")
    with robot.rpsl.perception_graph("fixed") as g:
        g.sensor("w", reads="force_sensor")
    robot.depsl.deployment_specification("force").add_constraint("attribute", "platform_has", "force_sensor").add_constraint("capacity", "memory", 50)
    robot.depsl.deployment_specification("fixed").executable_on("pc2")
    model = robot.build()
    clock = [0.0]
    repo = Repository(clock=lambda: clock[0])
    load_model(repo, model)
    return model, repo, clock


def test_the_model_is_loaded_with_the_design_vocabulary(world):
    _model, repo, _ = world
    labels = {d["label"] for _n, d in repo.graph.nodes(data=True)}
    assert labels == {L.PLATFORM, L.DEVICE, L.PERCEPTION_GRAPH, L.DEPLOYMENT, L.REQUIREMENT, L.ROBOT}
    q = RepositoryQuery(repo)
    assert [e[1] for e in q.match("Deployment", "EXECUTABLE_ON", "Platform")] == ["Platform:pc2"]
    assert len(list(q.match(edge_label="REQUIRES"))) == 2


def test_queries_answer_what_the_algorithms_ask(world):
    model, repo, _ = world
    q = RepositoryQuery(repo)
    spec = q.deployment_information("force")
    assert spec == model.spec("force")
    assert q.deployment_information("nonexistent") is None
    assert q.fixed_platform(q.deployment_information("fixed")) == "pc2"
    assert q.has_fixed_deployment(spec) is False
    assert q.constraints(spec) == model.spec("force").requirements
    assert [s.name for s in q.platform_states()] == ["pc1", "pc2"]
    control = ImmediateControl(repo)
    control.start("force", "pc1")
    assert q.is_deployed("force") and q.is_deployed("force", ("pc1",)) and not q.is_deployed("force", ("pc2",))
    assert q.active_deployments("pc1") == ("force",)
    assert q.perception_graph("force") == "force"
    assert q.platform_state("pc1").deployed == (("force", (("memory", 50),)),)


def test_unknown_names_raise_query_errors_naming_them(world):
    _m, repo, _ = world
    q = RepositoryQuery(repo)
    with pytest.raises(QueryError, match="unknown platform 'pc9'"):
        q.active_deployments("pc9")
    with pytest.raises(QueryError, match="unknown device 'cam'"):
        set_device_working(repo, "cam", False)


def test_a_device_failure_removes_and_a_repair_restores_the_has_device_edge(world):
    _m, repo, _ = world
    assert set_device_working(repo, "ft", False) == "pc1"
    assert not repo.graph.has_edge("Platform:pc1", "Device:ft", L.HAS_DEVICE)
    assert set_device_working(repo, "ft", False) is None  # nothing changes twice
    assert set_device_working(repo, "ft", True) == "pc1"
    assert repo.graph.has_edge("Platform:pc1", "Device:ft", L.HAS_DEVICE)


def test_stopping_relabels_deployed_on_to_history_with_start_and_stop_times(world):
    _m, repo, clock = world
    control = ImmediateControl(repo)
    clock[0] = 1.5
    control.start("force", "pc1")
    clock[0] = 4.0
    control.stop("force", "pc1")
    assert RepositoryQuery(repo).history() == (("force", "pc1", 1.5, 4.0),)
    assert not list(repo.edges(L.DEPLOYED_ON))


def test_notify_delivers_only_matching_frozen_changes(world):
    _m, repo, _ = world
    got, edges = [], []
    repo.subscribe(got.append, labels=[L.HAS_DEVICE], ops=["remove_edge"])
    repo.subscribe(edges.append, where=lambda c: c.source == "Deployment:force")
    set_platform_up(repo, "pc2", False)
    set_device_working(repo, "ft", False)
    ImmediateControl(repo).start("force", "pc1")
    assert [(c.op, c.source, c.target) for c in got] == [("remove_edge", "Platform:pc1", "Device:ft")]
    assert [c.label for c in edges] == [L.DEPLOYED_ON]
    with pytest.raises(AttributeError):
        got[0].time = 3  # frozen


def test_subscribing_to_an_unknown_op_is_rejected(world):
    _m, repo, _ = world
    with pytest.raises(QueryError, match="unknown change op"):
        repo.subscribe(print, ops=["delete"])


def test_a_cancelled_subscription_hears_nothing(world):
    _m, repo, _ = world
    got = []
    sub = repo.subscribe(got.append)
    sub.cancel()
    set_load(repo, "pc1", "memory", 10)
    assert got == []


def test_the_change_log_is_append_only_and_timestamped(world):
    _m, repo, clock = world
    n = len(repo.log)
    clock[0] = 7.0
    set_load(repo, "pc1", "memory", 100)
    log = repo.log
    assert len(log) == n + 1 and log[-1].time == 7.0 and log[-1].seq == n
    assert [c.seq for c in log] == list(range(len(log)))


def test_snapshot_rebuilds_the_graph_as_it_was_at_a_time(world):
    _m, repo, clock = world
    control = ImmediateControl(repo)
    clock[0] = 1.0
    set_context(repo, "r", "move_base")
    control.start("force", "pc1")
    clock[0] = 2.0
    set_device_working(repo, "ft", False)
    control.stop("force", "pc1")
    at1 = repo.snapshot(at=1.0)
    assert at1.has_edge("Deployment:force", "Platform:pc1", L.DEPLOYED_ON)
    assert at1.has_edge("Platform:pc1", "Device:ft", L.HAS_DEVICE)
    assert at1.has_edge("Robot:r", "Context:move_base", L.IN_CONTEXT)
    at2 = repo.snapshot(at=2.0)
    assert not at2.has_edge("Deployment:force", "Platform:pc1", L.DEPLOYED_ON)
    assert nx.utils.graphs_equal(at2, repo.graph)
    assert repo.snapshot(at=0.0).number_of_edges() < at1.number_of_edges()


def test_a_snapshot_exports_to_json_and_graphml(world, tmp_path):
    _m, repo, _ = world
    ImmediateControl(repo).start("force", "pc1")
    data = graph_to_json(repo.snapshot())
    text = json.dumps(data)
    assert any(e["label"] == "DEPLOYED_ON" for e in data["edges"])
    assert "Capacity(memory >= 50 MB)" in text
    path = tmp_path / "snap.graphml"
    graph_to_graphml(repo.snapshot(), str(path))
    back = nx.read_graphml(path)
    assert back.number_of_nodes() == repo.graph.number_of_nodes()
    assert back.number_of_edges() == repo.graph.number_of_edges()


def test_the_current_context_is_the_single_in_context_edge(world):
    _m, repo, _ = world
    q = RepositoryQuery(repo)
    assert q.context() is None
    assert set_context(repo, "r", "grasp") is True
    assert set_context(repo, "r", "grasp") is False
    set_context(repo, "r", "release")
    assert q.context() == "release"
    assert len(list(repo.edges(L.IN_CONTEXT))) == 1


def test_the_edge_index_agrees_with_the_graph_after_any_changes(world):
    _m, repo, clock = world
    control = ImmediateControl(repo)
    for i in range(5):
        clock[0] = float(i)
        control.start("force", "pc1")
        set_device_working(repo, "ft", i % 2 == 0)
        control.stop("force", "pc1")
    for nid in repo.graph.nodes:
        for label in L.EDGE_LABELS:
            out = sorted({t for _s, t, d in repo.graph.out_edges(nid, data=True) if d["label"] == label})
            into = sorted({s for s, _t, d in repo.graph.in_edges(nid, data=True) if d["label"] == label})
            assert sorted(repo.successors(nid, label)) == out
            assert sorted(repo.predecessors(nid, label)) == into
    assert len(RepositoryQuery(repo).history()) == 5


def _as_built(g: nx.MultiDiGraph) -> tuple:
    """A graph as a value, orders included: its nodes with their attributes, its edges
    with keys and attributes, in the graph's own order."""
    return list(g.nodes(data=True)), list(g.edges(keys=True, data=True))


def test_the_graph_read_at_any_moment_holds_every_change_so_far_in_the_replayed_order():
    """The networkx graph takes an edge change when it is next read (a simulation that
    reads only the Query port never pays for it): whenever it is read -- by a Notify
    subscriber in the middle of a run, or after it -- it is the graph the change log
    replays to, node and edge order included."""
    from pathlib import Path

    from desmon.loader import load_scenario
    from desmon.sim.engine import SimWorld

    root = Path(__file__).resolve().parents[1]
    world = SimWorld(load_scenario(root / "scenarios" / "robot_day.py", {"hours": "0.25"}), seed=3, reads=("exposure_s",))
    repo = world.repo
    read = []

    def compare(change):  # every 5th change: the graph read from inside a change's notification
        if change.seq % 5 == 0:
            read.append(change.seq)
            assert _as_built(repo.graph) == _as_built(repo.snapshot(upto=change.seq + 1)), change.describe()

    repo.subscribe(compare)
    world.run()
    assert len(read) > 50 and any(c.op == "relabel_edge" for c in repo.log)  # starts, stops and their history edges
    assert _as_built(repo.graph) == _as_built(repo.snapshot())


def test_query_memos_follow_every_change_they_read(world):
    from desmon.repository.facts import record_start, record_stop

    model, repo, _ = world
    q = RepositoryQuery(repo)
    before = q.platform_states()
    assert q.platform_states() is before  # nothing changed: the same tuple
    p = before[0].name
    set_load(repo, p, "memory", 123.0)
    after = q.platform_states()
    assert after is not before and after[0].load_of("memory") == 123.0 and after[1:] == before[1:]
    g = model.specs[0].graph
    record_start(repo, g, p)
    assert q.deployed_on(g) == (p,) and (g, p) in q.deployments() and g in q.active_deployments(p)
    assert g in dict(q.platform_state(p).deployed)
    record_stop(repo, g, p)
    assert q.deployed_on(g) == () and g not in q.active_deployments(p) and not q.platform_state(p).deployed
    set_load(repo, p, "memory", before[0].load_of("memory"))
    assert q.platform_state(p) is before[0]  # the same facts again: the same object


def test_equal_facts_of_another_type_are_not_handed_out_as_the_earlier_state(world):
    # 2 and 2.0 compare equal but print otherwise: each state says what the repository holds
    _model, repo, _ = world
    q = RepositoryQuery(repo)
    p = q.platform_states()[0].name
    set_load(repo, p, "memory", 2)
    seen = q.platform_state(p)
    set_load(repo, p, "memory", 77.0)
    q.platform_state(p)
    set_load(repo, p, "memory", 2.0)
    assert repr(q.platform_state(p).load_of("memory")) == "2.0"
    assert repr(seen.load_of("memory")) == "2"
