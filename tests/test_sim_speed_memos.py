"""The shortcuts of the deployment path answer exactly what the long
way answers, and every write that changes the facts changes the answer.

Each test below fails if its shortcut kept an answer past a write that changes it: a
platform state handed out again after a device failed, a view's validity kept for
another view, a rounding kept for another time, an inbox stimulus kept for other
platforms.
"""

from __future__ import annotations

import math
import pickle

import pytest
from conftest import force_robot_world
from hypothesis import given
from hypothesis import strategies as st

from desmon.deployment.invariants import SystemView, validly_active, validly_active_among, view_of
from desmon.deployment.monitor import Stimulus
from desmon.deployment.validity import deployment_valid
from desmon.errors import ModelError
from desmon.model import RobotBuilder
from desmon.model.checks import check_name, check_number, is_plain_name
from desmon.model.events import LoadChange
from desmon.model.system import PlatformState, new_platform_state
from desmon.repository import RepositoryQuery, set_device_working, set_load, set_platform_up
from desmon.repository.facts import record_start, record_stop
from desmon.repository.store import Change
from desmon.sim.driver import Inbox
from desmon.sim.trace import Trace


@pytest.fixture
def world():  # type: ignore[no-untyped-def]
    return force_robot_world()


# ---------------------------------------------------------------------------- platform states
def test_a_state_is_handed_out_again_only_for_equal_facts(world):
    _model, repo = world
    q = RepositoryQuery(repo)
    first = q.platform_state("pc1")
    set_load(repo, "pc1", "memory", 100.0)
    loaded = q.platform_state("pc1")
    assert loaded is not first and loaded.load == (("memory", 100.0),)
    set_load(repo, "pc1", "memory", 0.0)
    assert q.platform_state("pc1") is first  # the same facts again: the same object
    # a device failure is other facts: never the state that still lists the device
    set_device_working(repo, "ft", False)
    failed = q.platform_state("pc1")
    assert [d.name for d in failed.devices] == ["ft2"]
    set_device_working(repo, "ft2", False)
    assert q.platform_state("pc1").devices == ()
    set_device_working(repo, "ft", True)
    set_device_working(repo, "ft2", True)
    repaired = q.platform_state("pc1")
    assert repaired is first and [d.name for d in repaired.devices] == ["ft", "ft2"]
    set_platform_up(repo, "pc1", False)
    down = q.platform_state("pc1")
    assert down.up is False and down is not first
    set_platform_up(repo, "pc1", True)
    assert q.platform_state("pc1") is first


def test_a_state_is_not_handed_out_for_amounts_of_another_type(world):
    _model, repo = world
    q = RepositoryQuery(repo)
    set_load(repo, "pc1", "memory", 100.0)
    as_float = q.platform_state("pc1")
    set_load(repo, "pc1", "memory", 7.0)
    set_load(repo, "pc1", "memory", 100)  # equal to 100.0, but prints otherwise
    as_int = q.platform_state("pc1")
    assert as_int is not as_float and type(as_int.load[0][1]) is int


def test_a_state_follows_the_deployments(world):
    _model, repo = world
    q = RepositoryQuery(repo)
    empty = q.platform_state("pc1")
    record_start(repo, "force", "pc1")
    running = q.platform_state("pc1")
    assert running.deployed == (("force", (("memory", 50.0),)),)
    record_stop(repo, "force", "pc1")
    assert q.platform_state("pc1") is empty
    record_start(repo, "force", "pc1")
    assert q.platform_state("pc1") is running


def test_the_fast_state_builder_is_the_constructor():
    robot = RobotBuilder("r")
    robot.platform("pc", memory=512).device("ft", kind="force_sensor")
    model = robot.build()
    p, devices = model.platforms[0], model.devices
    args = (p, True, devices, (("memory", 10.0),), (("g", (("memory", 5.0),)),))
    built, made = new_platform_state(*args), PlatformState(*args)
    assert built == made and hash(built) == hash(made) and repr(built) == repr(made)
    assert pickle.loads(pickle.dumps(built)) == made
    bad = (p, True, (), (("memory", 1.0), ("memory", 2.0)), ())
    with pytest.raises(ModelError) as fast:
        new_platform_state(*bad)
    with pytest.raises(ModelError) as slow:
        PlatformState(*bad)
    assert str(fast.value) == str(slow.value)


# ---------------------------------------------------------------------------- change records
def test_change_records_equal_the_constructors(world):
    _model, repo = world
    set_load(repo, "pc1", "memory", 3.0)
    record_start(repo, "force", "pc1")
    record_stop(repo, "force", "pc1")
    for c in repo.log[-3:]:
        made = Change(c.seq, c.time, c.op, c.label, c.node, c.source, c.target, c.key, c.old_label, c.attrs)
        assert c == made and repr(c) == repr(made)
        if not any(isinstance(v, dict) for _k, v in c.attrs):  # a load is a dict: such a record is unhashable either way
            assert hash(c) == hash(made)
        with pytest.raises(AttributeError):
            c.seq = 0  # type: ignore[misc]
    # the log replays to the live graph (the attributes written are the record's)
    assert sorted(repo.snapshot().edges(keys=True, data=True), key=str) == sorted(repo.graph.edges(keys=True, data=True), key=str)
    assert dict(repo.snapshot().nodes(data=True)) == dict(repo.graph.nodes(data=True))


# ---------------------------------------------------------------------------- the audit's view
def test_a_views_validity_is_asked_once_and_is_its_own(world):
    model, repo = world
    q = RepositoryQuery(repo)
    record_start(repo, "force", "pc1")
    specs = model.specs
    view = view_of(q, specs, frozenset(), (("force",),))
    state = view.state("pc1")
    assert view.failures("force", state) == deployment_valid(model.spec("force"), state, view.states, view.checks) == ()
    assert validly_active(view) == validly_active_among(view.states, view.spec) == frozenset({"force"})
    # both devices fail: a new view says so (a view's answers are never another's)
    set_device_working(repo, "ft", False)
    set_device_working(repo, "ft2", False)
    later = view_of(q, specs, frozenset(), (("force",),))
    assert later.failures("force", later.state("pc1")) != ()
    assert validly_active(later) == frozenset()
    assert validly_active(view) == frozenset({"force"})  # the old view still describes its own facts
    # the caches are no part of a view's equality
    again = SystemView(later.states, later.specs, later.standing, later.slots)
    assert again == SystemView(later.states, later.specs, later.standing, later.slots, checks=None)


# ---------------------------------------------------------------------------- trace rounding
@pytest.mark.parametrize("times", [
    [1.23456789, 1.23456789, 2.5, 1.23456789],
    [0, 0.0, -0.0, 0, 1e-7, 1e-7],
    [3, 3.0, 3.0000004, 3.0000006],
])
def test_trace_rounding_is_rounds_for_every_time(times):
    trace = Trace()
    for t in times:
        assert repr(trace.rounded(t)) == repr(round(float(t), 6))
        trace.emit(t, "x", at=float(t))
        rec = trace.records[-1]
        assert repr(rec["t"]) == repr(round(float(t), 6)) and repr(rec["at"]) == repr(round(float(t), 6))
    # the same object in a row: the rounding of that object
    t = 7.1234567
    assert trace.rounded(t) == trace.rounded(t) == round(t, 6)
    assert trace.rounded(8.1234567) == round(8.1234567, 6)


# ---------------------------------------------------------------------------- the inbox
def test_the_inbox_hands_out_the_stimulus_of_what_it_collected(world):
    _model, repo = world
    inbox = Inbox(repo)
    inbox.add(("pc1",), ())
    a = inbox.take()
    assert a == Stimulus(("pc1",), False, ()) and not inbox.pending()
    inbox.add(("pc1",), ())
    assert inbox.take() is a
    inbox.add(("pc2",), ("force",))
    inbox.context = True
    b = inbox.take()
    assert b == Stimulus(("pc2",), True, ("force",))
    inbox.add(("pc1", "pc2"), ())
    assert inbox.take() == Stimulus(("pc1", "pc2"), False, ())


# ---------------------------------------------------------------------------- LoadChange checks
@pytest.mark.parametrize("platform, amount, resource", [
    ("pc", -1.0, "memory"), ("pc", math.nan, "memory"), ("pc", math.inf, "memory"), ("pc", True, "memory"),
    ("pc", "12", "memory"), ("a/b", 1.0, "memory"), ("  ", 1.0, "memory"), (3, 1.0, "memory"), ("pc", 1.0, "m\tem"),
])
def test_a_load_change_refuses_what_the_checks_refuse(platform, amount, resource):
    with pytest.raises(ModelError) as got:
        LoadChange(platform, amount, resource)
    with pytest.raises(ModelError) as expected:
        check_name("LoadChange platform", platform)
        check_name(f"LoadChange({platform!r}) resource", resource)
        check_number(f"load on {platform!r} {resource}", amount)
    assert str(got.value) == str(expected.value)


@pytest.mark.parametrize("name, plain", [
    ("pc", True), ("", False), (" ", False), ("a/b", False), ("a\nb", False), ("a\tb", False), (3, False), (None, False),
])
def test_a_plain_name_is_one_check_name_accepts(name, plain):
    assert is_plain_name(name) is plain
    if plain:
        assert check_name("x", name) == name
    else:
        with pytest.raises(ModelError):
            check_name("x", name)


@given(st.text(alphabet=st.sampled_from(list("ab /\n\t\r:-_.é\x00")), max_size=6))
def test_every_plain_name_is_one_check_name_accepts(name):
    """The LoadChange shortcut may only skip check_name for names it accepts: should
    check_name ever refuse more, this fails instead of the shortcut letting them in."""
    if is_plain_name(name):
        assert check_name("x", name) == name


# ---------------------------------------------------------------------------- Quantity
@pytest.mark.parametrize("working, need", [(0, 1), (1, 1), (2, 1), (1, 2), (2, 2), (3, 2)])
def test_quantity_counts_as_the_whole_count_says(working, need):
    from desmon.model.requirements import Quantity

    robot = RobotBuilder("r")
    pc = robot.platform("pc", memory=512)
    for i in range(3):
        pc.device(f"ft{i}", kind="force_sensor")
    pc.device("cam", kind="camera")
    model = robot.build()
    devices = tuple(d for d in model.devices if d.kind == "camera") + tuple(d for d in model.devices if d.kind == "force_sensor")[:working]
    state = PlatformState(model.platforms[0], True, devices)
    req = Quantity("force_sensor", need)
    have = sum(1 for d in devices if d.kind == "force_sensor")
    expected = None if have >= need else f"{have} working force_sensor device(s), needs {need}"
    assert req.holds(state, "g") == expected
