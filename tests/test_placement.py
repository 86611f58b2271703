"""The vectorised placement path answers exactly what the scalar check_validity answers."""

from __future__ import annotations

import pytest
from hypothesis import given, settings, strategies as st

from desmon.deployment import placement, validity
from desmon.deployment.memo import ColumnMemo
from desmon.deployment.placement import ChangeLogColumns, PlatformColumns
from desmon.errors import ModelError, QueryError
from desmon.model import Device, Platform, PlatformState, RobotBuilder, make_requirement as req
from desmon.model.requirements import Attribute, Capacity, Maximum, Minimum, Option, Quantity, Reads, Selection, overlapping_options
from desmon.repository import Repository, RepositoryQuery, load_model, set_device_working, set_load, set_platform_up
from desmon.repository.facts import record_start, record_stop

KINDS = ("pad", "cam", "ft")
VENDORS = ("weiss", "kuka")
GRAPHS = ("g0", "g1", "g2", "g3")
RESOURCES = ("memory", "cpu")
# amounts chosen so that sums land exactly on, or one rounding step beside, the thresholds
AMOUNTS = (0, 0.1, 0.2, 0.3, 0.5, 1, 1.5, 100, 150, 250, 256, 400, 512)
# "None": the text of what a platform without the attribute has, which meets no value
ATTR_VALUES = ("linux", "qnx", "1", 1, 1.0, 2, "None")


def scalar(reqs, states, graph, reasons):
    """The scalar loop itself (no memo, no columns)."""
    return validity.loop_validity(tuple(reqs), tuple(states), graph, reasons)


def columns_checks():
    """The fleet's Checks port: numpy columns from VECTOR_MIN_PLATFORMS platforms on, no memoised answer."""
    return placement.ColumnChecks()


# -- fleets ----------------------------------------------------------------------------------------
amounts = st.sampled_from(AMOUNTS) | st.floats(0, 600, allow_nan=False, allow_infinity=False)


@st.composite
def platform_states(draw, name: str) -> PlatformState:
    caps = draw(st.dictionaries(st.sampled_from(RESOURCES), amounts, max_size=2))
    platform = Platform(
        name,
        capacities=tuple(sorted(caps.items())),
        attributes=tuple(sorted(draw(st.dictionaries(st.sampled_from(("os", "arch")), st.sampled_from(ATTR_VALUES), max_size=2)).items())),
        properties=tuple(sorted(draw(st.dictionaries(st.sampled_from(("lat", "cores")), st.sampled_from((-1, 0, 0.5, 1, 2, 4.0, 8)), max_size=2)).items())),
        preference=draw(st.sampled_from((0.0, 0.0, 1.0, -1.0, 2.5))),
        on_demand=draw(st.booleans()),  # a down on-demand platform reads "not there"
    )
    devices = tuple(
        Device(f"{name}-d{j}", kind, name, vendor=vendor)
        for j, (kind, vendor) in enumerate(draw(st.lists(st.tuples(st.sampled_from(KINDS), st.sampled_from(VENDORS)), max_size=4)))
    )
    load = tuple(sorted(draw(st.dictionaries(st.sampled_from(RESOURCES), amounts, max_size=2)).items()))
    graphs = draw(st.lists(st.sampled_from(GRAPHS), unique=True, max_size=4))
    deployed = tuple(
        (g, tuple(sorted(draw(st.dictionaries(st.sampled_from(RESOURCES), amounts, min_size=1, max_size=2)).items())))
        for g in sorted(graphs)
    )
    return PlatformState(platform, up=draw(st.booleans() | st.just(True)), devices=devices, load=load, deployed=deployed)


@st.composite
def fleets(draw, min_size: int = 1, max_size: int = 12) -> tuple[PlatformState, ...]:
    n = draw(st.integers(min_size, max_size))
    return tuple(draw(platform_states(f"p{i}")) for i in range(n))


options = st.one_of(
    st.builds(Option, device_kind=st.sampled_from(KINDS), vendor=st.none() | st.sampled_from(VENDORS)),
    st.builds(Option, attribute=st.sampled_from(("os", "arch")), value=st.sampled_from(ATTR_VALUES)),
)
requirements = st.one_of(
    st.builds(Quantity, st.sampled_from(KINDS), st.integers(1, 3)),
    st.builds(Capacity, st.sampled_from(RESOURCES), amounts),
    st.builds(Minimum, st.sampled_from(("lat", "cores", "gpu")), st.sampled_from((-1, 0, 0.5, 1, 2, 4))),
    st.builds(Maximum, st.sampled_from(("lat", "cores")), st.sampled_from((-1, 0, 0.5, 1, 2, 4))),
    st.builds(Attribute, st.sampled_from(("os", "arch")), st.sampled_from(ATTR_VALUES)),
    st.builds(Attribute, st.just("platform_has"), st.sampled_from(KINDS)),
    st.lists(options, min_size=1, max_size=3, unique=True).flatmap(  # (an option listed twice is refused)
        lambda opts: st.builds(Selection, st.just(tuple(opts)), st.integers(1, 1 if overlapping_options(opts) else len(opts)))
    ),
    # what a graph's inputs require (its own half: a hosting platform needs a working device)
    st.builds(Reads, st.sampled_from(KINDS), st.lists(st.tuples(st.just("dev"), st.sampled_from([f"p{i}" for i in range(12)])), min_size=1, max_size=3).map(tuple)),
)
placings = st.none() | st.sampled_from((*GRAPHS, "g9")) | st.lists(st.sampled_from(GRAPHS), min_size=1, max_size=3).map(tuple)


def test_a_selection_option_naming_the_value_none_is_not_met_by_a_platform_without_the_attribute():
    """``Selection("gpu=None")`` held on a platform with no ``gpu`` attribute (its value read as
    the text "None"), where ``Attribute("gpu", "None")`` and the numpy columns said it fails."""
    bare = PlatformState(Platform("bare"), up=True)
    declared = PlatformState(Platform("declared", attributes=(("gpu", "None"),)), up=True)
    states = (bare, declared)
    for r in (Selection((Option.parse("gpu=None"),)), Attribute("gpu", "None")):
        want = scalar([r], states, "g0", True)
        assert want.acceptable == ("declared",), r
        assert PlatformColumns(states).validity([r], "g0", reasons=True) == want


@pytest.mark.parametrize("second, fits_too", [(0.8, True), (0.8 + 1e-6, False)])
def test_decimal_capacities_add_up_as_written_in_every_engine(second, fits_too):
    """1.2 GB holds 0.4 and 0.8 GB: in binary 1.2 - 0.4 is 0.7999999999999999, which had
    rejected the second graph ("0.8 free" as the reason for needing 0.8), while 0.4 + 0.8 is
    1.2000000000000002, which the no-overcommit invariant would have called an overcommit.
    The requirement, its columns, the invariant and the simulation agree; a millionth more does not fit."""
    from desmon.model.scenario import Scenario
    from desmon.sim.engine import simulate
    from desmon.sim.world import Step, World

    gpu = Platform("gpu_pc", capacities=(("vram_gb", 1.2),))
    state = PlatformState(gpu, up=True, deployed=(("seg", (("vram_gb", 0.4),)),))
    want = scalar([Capacity("vram_gb", second)], (state,), "det", True)
    assert want.acceptable == (("gpu_pc",) if fits_too else ())
    assert PlatformColumns((state,)).validity([Capacity("vram_gb", second)], "det", reasons=True) == want
    r = RobotBuilder("gb")
    r.platform("gpu_pc", memory=512, capacities={"vram_gb": 1.2}).device("ft", kind="force_sensor")
    for g, need in (("seg", 0.4), ("det", second)):
        with r.rpsl.perception_graph(g) as gb:
            gb.sensor("w", reads="force_sensor")
        r.depsl.deployment_specification(g).add_constraint("capacity", "vram_gb", need)
    r.rules({"hold": [("seg",), ("det",)]})
    sc = Scenario(name="gb", description="decimals", model=r.build(), world=World(task=(Step("hold", 10.0),), horizon=10.0, signals=False))
    run = simulate(sc, "desmon", seed=0)
    assert sorted(g for g, _p in RepositoryQuery(run.repo).deployments()) == (["det", "seg"] if fits_too else ["seg"])
    assert run.violations == [] and ({e.kind for e in run.errors} == {"no_acceptable_platforms"}) == (not fits_too)
    both = PlatformState(gpu, up=True, deployed=(("seg", (("vram_gb", 0.4),)), ("det", (("vram_gb", second),))))
    assert overcommitted(both) == (not fits_too)


def overcommitted(state: PlatformState) -> bool:
    """Whether the no-overcommit invariant finds ``state`` overcommitted."""
    from desmon.deployment.invariants import _no_overcommit

    class View:
        states = (state,)

    return _no_overcommit(View()) is not None  # type: ignore[arg-type]


# -- exactness -------------------------------------------------------------------------------------
@pytest.mark.slow
@given(fleets(), st.lists(requirements, max_size=4), placings, st.booleans())
@settings(max_examples=100)
def test_columns_give_the_same_validity_as_check_validity(states, reqs, graph, reasons):
    cols = PlatformColumns(states)
    want = scalar(reqs, states, graph, reasons)
    assert cols.validity(reqs, graph, reasons=reasons) == want
    assert cols.acceptable(reqs, graph) == want.acceptable


@pytest.mark.slow
@given(fleets(), st.lists(requirements, min_size=1, max_size=3), placings)
@settings(max_examples=40)
def test_the_reasons_memo_answers_a_repeated_question_as_the_first_time(states, reqs, graph):
    for kept in (placement._REASONS_KEPT, 2):  # 2: the memo evicts all the time
        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(placement, "_REASONS_KEPT", kept)
            cols = PlatformColumns(states)
            for reasons in (False, True, False, True):
                assert cols.validity(reqs, graph, reasons=reasons) == scalar(reqs, states, graph, reasons)
                assert cols.validity(reqs[:1], "g1", reasons=reasons) == scalar(reqs[:1], states, "g1", reasons)


@pytest.mark.slow
@given(fleets(min_size=3, max_size=8), st.data(), st.lists(requirements, min_size=1, max_size=3), placings)
@settings(max_examples=40)
def test_rewriting_changed_rows_answers_as_a_rebuild(before, data, reqs, graph):
    # new facts for some platforms (same names): what a repository event changes
    changed = data.draw(st.lists(st.integers(0, len(before) - 1), unique=True, min_size=1))
    after = list(before)
    for i in changed:
        after[i] = data.draw(platform_states(before[i].name))
    after = tuple(after)
    via_update, via_sync = PlatformColumns(before), PlatformColumns(before)
    for cols in (via_update, via_sync):  # warm the reasons memo with the old facts
        cols.validity(reqs, graph, reasons=True)
        cols.validity(reqs, graph, reasons=False)
    via_update.update({i: after[i] for i in changed})
    assert via_sync.sync(after)
    for reasons in (True, False):
        want = scalar(reqs, after, graph, reasons)
        assert PlatformColumns(after).validity(reqs, graph, reasons=reasons) == want
        assert via_update.validity(reqs, graph, reasons=reasons) == want
        assert via_sync.validity(reqs, graph, reasons=reasons) == want


@given(fleets(min_size=2, max_size=6), st.lists(requirements, min_size=1, max_size=3), placings)
@settings(max_examples=30)
def test_capacity_sums_left_to_scalar_code_under_compensated_sum_still_agree(states, reqs, graph):
    with pytest.MonkeyPatch.context() as mp:  # what Python >= 3.12 does (its sum compensates)
        mp.setattr(placement, "_COMPENSATED_SUM", True)
        assert PlatformColumns(states).validity(reqs, graph) == scalar(reqs, states, graph, True)


def test_float_shares_are_summed_in_the_scalar_order():
    # 0.1 + 0.2 > 0.3 in float64: free = 0.6 - (0.1 + 0.2) - 0 is just below 0.3
    p = Platform("pc", capacities=(("memory", 0.6),))
    s = PlatformState(p, deployed=(("a", (("memory", 0.1),)), ("b", (("memory", 0.2),))))
    states = (s,)
    for amount in (0.3, 0.29999999999999993, 0.30000000000000004):
        reqs = (Capacity("memory", amount),)
        assert PlatformColumns(states).validity(reqs, "x") == scalar(reqs, states, "x", True)


# -- dispatch --------------------------------------------------------------------------------------
def big_fleet(n: int) -> tuple[PlatformState, ...]:
    out = []
    for i in range(n):
        p = Platform.make(f"pc{i}", memory=(256, 512, 1024)[i % 3], attributes={"os": ("linux", "qnx")[i % 2]}, preference=float(i % 4 == 0))
        devices = tuple(Device(f"pc{i}-d{j}", KINDS[(i + j) % 3], f"pc{i}", vendor=VENDORS[j % 2]) for j in range(i % 4))
        deployed = (("g0", (("memory", 150.0),)),) if i % 5 == 0 else ()
        out.append(PlatformState(p, up=i % 7 != 3, devices=devices, load=(("memory", float(i % 300)),), deployed=deployed))
    return tuple(out)


FLEET_REQS = (req("capacity", "memory", 250), req("attribute", "os", "linux"), req("quantity", "pad", 1))


def test_check_validity_takes_the_columns_at_the_threshold_and_answers_the_same():
    states = big_fleet(placement.VECTOR_MIN_PLATFORMS)
    checks = columns_checks()
    got = validity.check_validity(FLEET_REQS, states, "g0", reasons=True, checks=checks)
    assert checks.columns.counts == {"vector": 1, "declined": 0}
    assert got == scalar(FLEET_REQS, states, "g0", True)


def test_check_validity_keeps_the_scalar_loop_below_the_threshold():
    states = big_fleet(placement.VECTOR_MIN_PLATFORMS - 1)
    checks = columns_checks()
    validity.check_validity(FLEET_REQS, states, "g0", checks=checks)
    assert checks.columns.counts == {"vector": 0, "declined": 0}


def test_the_scalar_checks_never_take_the_columns_however_many_platforms():
    states = big_fleet(placement.VECTOR_MIN_PLATFORMS * 2)
    got = validity.check_validity(FLEET_REQS, states, None, reasons=False, checks=validity.ScalarChecks())
    assert not hasattr(validity.ScalarChecks(), "columns")
    assert got == scalar(FLEET_REQS, states, None, False)


def test_a_requirement_the_columns_do_not_cover_falls_back_to_the_scalar_loop():
    preference_type = getattr(__import__("desmon.model.requirements", fromlist=["Preference"]), "Preference", None)
    if preference_type is None:
        pytest.skip("no soft preferences in this version")
    pref = preference_type("attribute", ("os", "linux"))
    reqs = (*FLEET_REQS, pref)
    states = big_fleet(placement.VECTOR_MIN_PLATFORMS)
    assert not placement.supported(reqs)
    checks = columns_checks()
    got = validity.check_validity(reqs, states, "g0", checks=checks)
    assert checks.columns.counts == {"vector": 0, "declined": 1}
    assert got == scalar(reqs, states, "g0", True)


def test_integers_too_large_for_float64_make_the_columns_decline():
    states = list(big_fleet(placement.VECTOR_MIN_PLATFORMS))
    states[5] = PlatformState(Platform("pc5", capacities=(("memory", 2**60 + 1),)))
    cols = PlatformColumns(states)
    assert not cols.exact
    assert placement.vector_validity(FLEET_REQS, tuple(states), "g0", False) is None
    assert not placement.supported((Capacity("memory", 2**60 + 1),))


def test_the_acceptable_shortcut_matches_check_validity_on_both_sides_of_the_threshold():
    for n in (placement.VECTOR_MIN_PLATFORMS - 1, placement.VECTOR_MIN_PLATFORMS * 3):
        states = big_fleet(n)
        assert placement.acceptable(FLEET_REQS, states, ("g0", "g1")) == scalar(FLEET_REQS, states, ("g0", "g1"), False).acceptable


def test_a_kept_store_is_rewritten_row_by_row_for_a_repository_style_fresh_but_equal_list():
    states = big_fleet(placement.VECTOR_MIN_PLATFORMS * 2)
    memo = ColumnMemo()
    first = placement.columns_for(states, memo)
    fresh = tuple(PlatformState(s.platform, s.up, s.devices, s.load, s.deployed) for s in states)
    moved = list(fresh)
    moved[3] = PlatformState(fresh[3].platform, up=not fresh[3].up, devices=fresh[3].devices, load=fresh[3].load)
    assert placement.columns_for(fresh, memo) is first
    assert placement.columns_for(tuple(moved), memo) is first
    assert placement.columns_for(states) is not first  # without a memo nothing is kept
    assert first.validity(FLEET_REQS, "g1") == scalar(FLEET_REQS, moved, "g1", True)


# -- strict inputs ---------------------------------------------------------------------------------
def test_columns_refuse_something_that_is_not_a_platform_state():
    with pytest.raises(ModelError, match=r"item 1 = 'pc' is not a PlatformState"):
        PlatformColumns((big_fleet(1)[0], "pc"))


def test_update_refuses_a_row_outside_the_list_or_another_platform():
    cols = PlatformColumns(big_fleet(3))
    with pytest.raises(QueryError, match=r"row 3 is not an index in 0..2"):
        cols.update({3: big_fleet(1)[0]})
    with pytest.raises(QueryError, match=r"row 1 holds platform 'pc1', not 'pc0'"):
        cols.update({1: big_fleet(1)[0]})


# -- following the change log ----------------------------------------------------------------------
@pytest.fixture
def world():
    robot = RobotBuilder("r")
    for i in range(6):
        robot.platform(f"pc{i}", memory=512, attributes={"os": "linux" if i % 2 else "qnx"}).device(f"ft{i}", kind="force_sensor")
    for g in ("force", "other"):
        with robot.rpsl.perception_graph(g) as pg:
            pg.sensor("w", reads="force_sensor")
        robot.depsl.deployment_specification(g).add_constraint("attribute", "platform_has", "force_sensor").add_constraint("capacity", "memory", 200)
    repo = Repository()
    load_model(repo, robot.build())
    return repo, RepositoryQuery(repo)


def test_change_log_columns_re_read_only_the_platforms_a_change_touched(world):
    repo, query = world
    follower = ChangeLogColumns(repo, query)
    reqs = (req("attribute", "platform_has", "force_sensor"), req("capacity", "memory", 200))
    events = [
        lambda: set_load(repo, "pc1", "memory", 300.0),
        lambda: set_platform_up(repo, "pc2", False),
        lambda: set_device_working(repo, "ft3", False),
        lambda: record_start(repo, "force", "pc4"),
        lambda: record_start(repo, "other", "pc4"),
        lambda: record_stop(repo, "force", "pc4"),
        lambda: set_device_working(repo, "ft3", True),
    ]
    follower.columns()
    reads = follower.reads
    for event in events:
        event()
        cols = follower.columns()
        assert follower.reads == reads + 1  # the one platform the event touched
        reads = follower.reads
        states = query.platform_states()
        assert follower.states() == states
        for graph in ("force", "other", None):
            assert cols.validity(reqs, graph) == scalar(reqs, states, graph, True)
    follower.close()
    set_load(repo, "pc0", "memory", 500.0)
    assert follower.reads == reads
