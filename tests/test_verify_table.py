"""The table engine: the real core run once per distinct reading, the direct engine's result."""

from __future__ import annotations

import dataclasses
import itertools
import json
import os
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as hst

from desmon.cli import main
from desmon.deployment import validity
from desmon.deployment.deployer import DESMON, Deployer
from desmon.deployment.ports import NO_ACCEPTABLE_PLATFORMS, RaiseError
from desmon.errors import CheckerError, NondeterminismError
from desmon.loader import load_scenario
from desmon.model import GRASP, HOLD, MOVE_BASE, RELEASE, RobotBuilder
from desmon.model.events import ActionChange, DeviceFail, LoadChange, PlatformDown
from desmon.model.scenario import Scenario, TimedEvent
from desmon.verify import Bounds, Checker
from desmon.verify.mutants import MUTANTS
from desmon.verify.table.tree import LEAF, WIDE
from desmon.errors import TableUnsupported, UnobservedRead

SCENARIOS = Path(__file__).resolve().parent.parent / "scenarios"
NAMES = sorted(p.stem for p in SCENARIOS.glob("*.py"))
OPTIONS = ({}, {"keep_going": True}, {"max_states": 30}, {"max_depth": 3})


def _everything(r, c):  # type: ignore[no-untyped-def]
    """Every part of a result a user can see, counterexample steps included."""
    return (
        r.verdict, r.reason, r.states, r.transitions, r.depth,
        dict(r.enabled), dict(r.new_states), dict(r.changed), dict(r.rules), dict(r.branches),
        [(x.invariant, x.message, x.during, [(s.title(), s.changes, s.commands, s.key) for s in x.steps]) for x in r.counterexamples],
        list(c.explored),
    )


def _both(scenario, deployer, **kw):  # type: ignore[no-untyped-def]
    direct = Checker(scenario, deployer)
    rd = direct.run(engine="direct", **kw)
    table = Checker(scenario, deployer)
    rt = table.run(engine="table", **kw)
    assert (rd.engine, rt.engine) == ("direct", "table")
    return _everything(rd, direct), _everything(rt, table), rt


@pytest.mark.slow
@pytest.mark.parametrize("deployer", ["desmon", "paper"])
@pytest.mark.parametrize("name", NAMES)
def test_table_engine_gives_the_direct_engines_result_on_every_scenario(name, deployer):
    scenario = load_scenario(SCENARIOS / f"{name}.py")
    for kw in OPTIONS:
        d, t, _r = _both(scenario, deployer, **kw)
        assert t == d, (name, deployer, kw)


@pytest.mark.parametrize(
    "name, mutant",
    [("coffee_handover", "no-recheck"), ("migration", "capacity-blind"),
     ("migration", "make-before-break"), ("robot_day", "make-before-break"), ("fallbacks", "stale-errors")],
)
def test_table_engine_catches_each_mutant_with_the_same_counterexamples(name, mutant):
    scenario = load_scenario(SCENARIOS / f"{name}.py")
    for kw in ({}, {"keep_going": True}):
        d, t, r = _both(scenario, MUTANTS[mutant], **kw)
        assert t == d
        assert r.verdict == "VIOLATED"


def test_the_real_core_runs_far_fewer_times_than_there_are_transitions():
    r = Checker(load_scenario(SCENARIOS / "coffee_handover.py")).run(engine="table")
    assert r.engine == "table" and r.verdict == "HOLDS"
    assert 0 < r.records < r.transitions / 5


def _peeking(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    # a deployer that reads background load directly, not through a requirement check
    if sum(s.load_of("memory") for s in q.platform_states()) > 10**9:
        return
    yield from DESMON.react(q, slots, changed, context_changed)


PEEKING = Deployer("peeking", "reads platform load outside validity", _peeking)


def test_a_deployer_reading_platform_facts_directly_is_refused_by_the_table_engine():
    with pytest.raises(UnobservedRead, match=r"test_verify_table read `load` of platform .* outside the requirement checks.*--engine direct"):
        Checker(load_scenario(SCENARIOS / "coffee_handover.py"), PEEKING).run(engine="table")


def _store_peeking(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    if getattr(q, "failed", ()):  # the checker's store has it; the QueryPort does not
        return
    yield from DESMON.react(q, slots, changed, context_changed)


def _dict_peeking(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    if any(dataclasses.asdict(s)["load"] for s in q.platform_states()):
        return
    yield from DESMON.react(q, slots, changed, context_changed)


@pytest.mark.parametrize(
    "react, message",
    [(_store_peeking, "asked its Query port for `failed`"), (_dict_peeking, "cannot observe .*asdict")],
)
def test_reads_around_the_query_port_or_through_dataclass_helpers_are_refused(react, message):
    # a platform state of a recorded run is an opaque handle: no dataclass helper reads it
    with pytest.raises(TableUnsupported, match=message):
        Checker(load_scenario(SCENARIOS / "coffee_handover.py"), Deployer("sly", "", react)).run(engine="table")


def _helper_peeking(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    # a public helper of the validity module, called outside a requirement check
    spec = q.deployment_information("force_slip_detector")
    if spec is not None and any(validity.requirement_holds(r, s, spec.graph) for s in q.platform_states() for r in spec.requirements):
        yield RaiseError(NO_ACCEPTABLE_PLATFORMS, spec.graph, None, "peeked")
    yield from DESMON.react(q, slots, changed, context_changed)


def test_a_validity_helper_called_by_the_deployer_is_refused_like_any_read():
    # (keep_going: its bogus error in the initial reaction is a violation at 0 steps, which alone ends a search)
    with pytest.raises(UnobservedRead, match=r"test_verify_table read `\w+` of platform"):
        Checker(load_scenario(SCENARIOS / "coffee_handover.py"), Deployer("helper", "", _helper_peeking)).run(engine="table", keep_going=True)


def _counting(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    # decides on how many requirements one platform fails, not just whether it fails
    for g in sorted({g for slot in slots for g in slot}):
        spec = q.deployment_information(g)
        if spec is not None and any(len(validity.check_platform(spec.requirements, s, g)) >= 2 for s in q.platform_states()):
            yield RaiseError(NO_ACCEPTABLE_PLATFORMS, g, None, "badly broken")
    yield from DESMON.react(q, slots, changed, context_changed)


def test_decisions_on_how_many_requirements_fail_are_replayed_exactly():
    d, t, r = _both(load_scenario(SCENARIOS / "memory_pressure.py"), Deployer("counting", "", _counting), keep_going=True)
    assert t == d
    assert r.branches["error no_acceptable_platforms"] > 0


def _joining(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    # str.join needs real strings: the table engine's explanation is not one
    for g in sorted({g for slot in slots for g in slot}):
        spec = q.deployment_information(g)
        if spec is not None and "load" in "\n".join([validity.validity_for(q, spec).explain()]):
            yield RaiseError(NO_ACCEPTABLE_PLATFORMS, g, None, "loaded")
    yield from DESMON.react(q, slots, changed, context_changed)


def test_an_explanation_used_as_a_plain_str_makes_auto_run_the_direct_engine():
    scenario = load_scenario(SCENARIOS / "memory_pressure.py")
    joining = Deployer("joining", "", _joining)
    with pytest.raises(TableUnsupported, match="cannot observe .*--engine direct"):
        Checker(scenario, joining).run(engine="table")
    auto, direct = Checker(scenario, joining).run(), Checker(scenario, joining).run(engine="direct")
    assert auto.engine == "direct" and "cannot observe" in auto.engine_note
    assert (auto.verdict, auto.states, auto.transitions) == (direct.verdict, direct.states, direct.transitions)


def _comparing(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    states = q.platform_states()
    if states[0] == states[-1]:  # equality of two states compares their facts
        return
    yield from DESMON.react(q, slots, changed, context_changed)


def test_comparing_two_platform_states_is_a_read_of_their_facts():
    with pytest.raises(UnobservedRead, match=r"test_verify_table read the facts \(comparing states\)"):
        Checker(load_scenario(SCENARIOS / "coffee_handover.py"), Deployer("comparing", "", _comparing)).run(engine="table")


def _buggy(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    if changed:
        q.deployment_information("force_slip_detector").no_such_field  # the deployer's own bug
    yield from DESMON.react(q, slots, changed, context_changed)


def test_a_deployers_own_error_surfaces_as_it_is_not_as_an_engine_limit():
    # an AttributeError of the deployer's own (not of a check result the table engine
    # wraps): every engine reports the crash, with the same shortest path to it
    paths = set()
    for engine in ("table", "auto", "direct"):
        res = Checker(load_scenario(SCENARIOS / "coffee_handover.py"), Deployer("buggy", "", _buggy)).run(engine=engine)
        assert res.verdict == "CRASHED" and res.exit_code == 4 and res.engine == ("direct" if engine == "direct" else "table")
        (c,) = res.counterexamples
        assert "raised AttributeError" in c.message and "no_such_field" in c.message
        paths.add(tuple(str(s.event) for s in c.steps))
    assert len(paths) == 1


def test_a_deployer_that_is_not_a_function_of_its_readings_is_reported_as_nondeterministic():
    calls = itertools.count()

    def flaky(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
        if next(calls) % 7 == 3:  # state kept outside the ports
            return
        yield from DESMON.react(q, slots, changed, context_changed)

    with pytest.raises(NondeterminismError, match="not a function of what it reads through its ports"):
        Checker(load_scenario(SCENARIOS / "coffee_handover.py"), Deployer("flaky", "", flaky)).run(engine="table")


class _Resized:
    """A port that shows every platform with 100 MB less memory (rewrites the platform itself)."""

    validity_memo = None

    def __init__(self, inner):  # type: ignore[no-untyped-def]
        self.inner = inner

    def platform_states(self):  # type: ignore[no-untyped-def]
        return tuple(
            dataclasses.replace(s, platform=dataclasses.replace(s.platform, capacities=tuple((r, a - 100) for r, a in s.platform.capacities)))
            for s in self.inner.platform_states()
        )

    def __getattr__(self, name):  # type: ignore[no-untyped-def]
        return getattr(self.inner, name)


def test_a_port_that_swaps_the_platform_itself_is_refused():
    def react(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
        yield from DESMON.react(_Resized(q), slots, changed, context_changed)

    # its copies of the platform states (dataclasses.replace) cannot be made of opaque handles
    with pytest.raises(TableUnsupported, match="rewrites platform facts|cannot observe"):
        Checker(load_scenario(SCENARIOS / "memory_pressure.py"), Deployer("resized", "", react)).run(engine="table")
    auto = Checker(load_scenario(SCENARIOS / "memory_pressure.py"), Deployer("resized", "", react)).run()
    assert auto.engine == "direct"


def test_a_platform_with_too_many_fact_combinations_runs_on_the_direct_engine():
    r = RobotBuilder("many")
    r.platform("pc0", memory=512).devices([f"pad{i}" for i in range(14)], kind="tactile_pad")
    with r.rpsl.perception_graph("tactile") as gb:
        gb.sensor("s", reads="tactile_pad")
        gb.processing("p", inputs=["s"])
    r.depsl.deployment_specification("tactile").add_constraint("quantity", "tactile_pad", 2)
    r.rules({HOLD: "tactile", GRASP: "tactile"})
    scenario = Scenario(
        name="many_pads", model=r.build(), timeline=(TimedEvent(0, ActionChange(HOLD)),),
        checker=Bounds(actions=(HOLD, GRASP), devices=tuple(f"pad{i}" for i in range(13)), max_failures=1),
    )
    with pytest.raises(CheckerError, match=r"platform pc0 has 8,192 combinations of facts"):
        Checker(scenario).run(engine="table")
    auto = Checker(scenario).run()
    assert auto.engine == "direct" and "8,192 combinations" in auto.engine_note and auto.verdict == "HOLDS"


def test_the_recording_port_offers_exactly_the_query_port_methods():
    from desmon.deployment.ports import QueryPort
    from desmon.deployment.ports import QUERY_METHODS as _QUERY_METHODS

    protocol = {n for n, v in vars(QueryPort).items() if callable(v) and not n.startswith("_")}
    assert set(_QUERY_METHODS) == protocol
    from desmon.verify.table.recording import RecordingQuery

    assert {n for n, v in vars(RecordingQuery).items() if callable(v) and not n.startswith("_")} == protocol


def test_auto_falls_back_to_the_direct_engine_and_says_why():
    scenario = load_scenario(SCENARIOS / "coffee_handover.py")
    auto = Checker(scenario, PEEKING).run()
    direct = Checker(scenario, PEEKING).run(engine="direct")
    assert auto.engine == "direct" and "outside the requirement checks" in auto.engine_note
    assert "--engine direct" not in auto.engine_note  # it ran: the note gives the reason, not advice
    assert (auto.verdict, auto.states, auto.transitions) == (direct.verdict, direct.states, direct.transitions)


class _AllUp:
    """A port that shows every platform up (rewrites platform facts)."""

    validity_memo = None

    def __init__(self, inner):  # type: ignore[no-untyped-def]
        self.inner = inner

    def platform_states(self):  # type: ignore[no-untyped-def]
        return tuple(dataclasses.replace(s, up=True) for s in self.inner.platform_states())

    def __getattr__(self, name):  # type: ignore[no-untyped-def]
        return getattr(self.inner, name)


def _optimist(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    yield from DESMON.react(_AllUp(q), slots, changed, context_changed)


def test_a_port_that_rewrites_platform_facts_is_refused_by_the_table_engine():
    with pytest.raises(TableUnsupported, match="rewrites platform facts|cannot observe"):
        Checker(load_scenario(SCENARIOS / "coffee_handover.py"), Deployer("optimist", "", _optimist)).run(engine="table")


def _picky(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    # decides on the *text* of the rejection reasons: the table engine must observe them
    for g in sorted({g for slot in slots for g in slot}):
        spec = q.deployment_information(g)
        if spec is not None and "load 300" in validity.validity_for(q, spec).explain():
            yield RaiseError(NO_ACCEPTABLE_PLATFORMS, g, None, "picky")
    yield from DESMON.react(q, slots, changed, context_changed)


def test_decisions_on_the_text_of_rejection_reasons_are_replayed_exactly():
    scenario = load_scenario(SCENARIOS / "coffee_handover.py")
    d, t, r = _both(scenario, Deployer("picky", "", _picky), keep_going=True)
    assert t == d
    assert r.branches["error no_acceptable_platforms"] > 0


def test_verify_reports_the_engine_and_direct_gives_the_same_counts(capsys, tmp_path):
    path = str(SCENARIOS / "coffee_handover.py")
    assert main(["verify", path, "--no-progress", "--json", str(tmp_path / "t.json")]) == 0
    table = capsys.readouterr().out
    assert main(["verify", path, "--no-progress", "--engine", "direct", "--json", str(tmp_path / "d.json")]) == 0
    direct = capsys.readouterr().out
    assert "engine: table (" in table and "engine: direct" in direct
    t, d = json.loads((tmp_path / "t.json").read_text()), json.loads((tmp_path / "d.json").read_text())
    assert (t["engine"], d["engine"]) == ("table", "direct")
    assert (t["states"], t["transitions"], t["verdict"]) == (d["states"], d["transitions"], d["verdict"])


def test_engine_table_with_workers_is_a_one_line_usage_error(capsys):
    path = str(SCENARIOS / "symmetric_platforms.py")
    assert main(["verify", path, "--no-progress", "--engine", "table", "--workers", "2"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--workers" in err[0]
    with pytest.raises(CheckerError, match="unknown engine 'fast'"):
        Checker(load_scenario(path)).run(engine="fast")


@pytest.mark.parametrize("deployer", ["desmon", "no-recheck"])
def test_under_symmetry_the_table_engine_gives_the_direct_engines_result(deployer):
    """The same orbits, in the same order, the same counts, counterexamples and states they cover."""
    scenario = load_scenario(SCENARIOS / "symmetric_platforms.py")
    dep = deployer if deployer == "desmon" else MUTANTS[deployer]
    for kw in OPTIONS:
        direct, table = Checker(scenario, dep, symmetry=True), Checker(scenario, dep, symmetry=True)
        rd, rt = direct.run(engine="direct", **kw), table.run(engine="table", **kw)
        assert (rd.engine, rt.engine, rt.symmetry) == ("direct", "table", True)
        assert _everything(rt, table) == _everything(rd, direct), kw
        assert rt.states_covered == rd.states_covered
    assert (rt.verdict, rt.states) == (("VIOLATED", 8) if deployer != "desmon" else ("INCOMPLETE", 147))  # the last: max_depth 3


def test_a_group_platform_down_for_the_whole_search_leaves_symmetry_to_the_direct_engine():
    """Its code holds no digit for that platform's down: auto says why and runs the direct engine."""
    sc = load_scenario(SCENARIOS / "symmetric_platforms.py")
    sc = dataclasses.replace(sc, initial=(*sc.initial, PlatformDown("e2")), checker=dataclasses.replace(sc.checker, platforms=("arm_pc",)))
    auto, direct = Checker(sc, symmetry=True).run(), Checker(sc, symmetry=True).run(engine="direct")
    assert auto.engine == "direct" and "stays down or failed for the whole search" in auto.engine_note
    assert (auto.verdict, auto.states, auto.states_covered) == (direct.verdict, direct.states, direct.states_covered)
    with pytest.raises(TableUnsupported, match="run with --engine direct"):
        Checker(sc, symmetry=True).run(engine="table")


def test_symmetry_runs_on_the_table_engine_unless_asked_otherwise(capsys):
    path = str(SCENARIOS / "symmetric_platforms.py")
    assert main(["verify", path, "--no-progress", "--symmetry"]) == 0
    out = capsys.readouterr().out
    assert "engine: table" in out and "states: 475 (orbits covering 1,748 states)" in out
    assert main(["verify", path, "--no-progress", "--symmetry", "--engine", "direct"]) == 0
    out = capsys.readouterr().out
    assert "engine: direct" in out and "states: 475 (orbits covering 1,748 states)" in out


# -- generated models: the encoding meets constant facts, task automata, loads, fixed graphs --

ACTIONS = (HOLD, GRASP, MOVE_BASE, RELEASE)


@hst.composite
def generated_scenarios(draw):  # type: ignore[no-untyped-def]
    n = draw(hst.integers(2, 4))
    r = RobotBuilder("gen")
    plats, devices = [f"pc{i}" for i in range(n)], []
    for i, p in enumerate(plats):
        pb = r.platform(p, memory=draw(hst.sampled_from((256, 400, 512))), preference=draw(hst.integers(0, 2)))
        kind = ("force", "pads")[i] if i < 2 else draw(hst.sampled_from(("force", "pads", "none")))
        if kind == "force":
            pb.device(f"wrench{i}", kind="force_sensor")
            devices.append(f"wrench{i}")
        elif kind == "pads":
            pb.devices([f"pad{i}a", f"pad{i}b"], kind="tactile_pad")
            devices += [f"pad{i}a", f"pad{i}b"]
    for g, reads in (("force", "force_sensor"), ("tactile", "tactile_pad"), ("combined", "force_sensor")):
        with r.rpsl.perception_graph(g) as gb:
            gb.sensor("s", reads=reads)
            gb.processing("p", inputs=["s"])
    r.depsl.deployment_specification("force").add_constraint("attribute", "platform_has", "force_sensor").add_constraint(
        "capacity", "memory", draw(hst.sampled_from((100, 200))))
    r.depsl.deployment_specification("tactile").add_constraint("quantity", "tactile_pad", 2).add_constraint("capacity", "memory", 150)
    combined = r.depsl.deployment_specification("combined").add_constraint("capacity", "memory", draw(hst.sampled_from((150, 250))))
    if draw(hst.booleans()):
        combined.executable_on(draw(hst.sampled_from(plats)))
    graphs = ["force", "tactile", "combined"]
    # a context wants one or two graphs at once, or one slot of alternatives (fallbacks)
    bodies = hst.one_of(
        hst.lists(hst.sampled_from(graphs), min_size=1, max_size=2, unique=True),
        hst.lists(hst.sampled_from(graphs), min_size=2, max_size=3, unique=True).map(lambda gs: [tuple(gs)]),
    )
    r.rules({a: draw(bodies) for a in ACTIONS})
    model = r.build()
    actions = draw(hst.lists(hst.sampled_from(ACTIONS), min_size=2, max_size=4, unique=True))
    task = None
    if draw(hst.booleans()):
        task = {a: tuple(draw(hst.lists(hst.sampled_from(actions), max_size=2, unique=True))) for a in actions}
    moving = draw(hst.lists(hst.sampled_from(plats), max_size=n, unique=True))
    loaded = draw(hst.lists(hst.sampled_from(plats), max_size=2, unique=True))
    failing = draw(hst.lists(hst.sampled_from(devices), max_size=3, unique=True)) if devices else []
    initial = [LoadChange(p, 0) for p in loaded]
    # facts the environment never changes: a load on an unbounded platform, a failed
    # device or a platform down that the bounds do not name
    rest = [p for p in plats if p not in loaded]
    if rest and draw(hst.booleans()):
        initial.append(LoadChange(draw(hst.sampled_from(rest)), 100))
    still = [d for d in devices if d not in failing]
    if still and draw(hst.booleans()):
        initial.append(DeviceFail(draw(hst.sampled_from(still))))
    fixed_up = [p for p in plats if p not in moving]
    if fixed_up and draw(hst.booleans()):
        initial.append(PlatformDown(draw(hst.sampled_from(fixed_up))))
    bounds = Bounds(
        actions=tuple(actions) if task is None else (), task=task, initial_action=actions[0], devices=tuple(failing),
        repair=draw(hst.booleans()), platforms=tuple(moving),
        loads={p: (0, 100, 200, 300)[: draw(hst.integers(2, 4))] for p in loaded},
        start_failures=draw(hst.integers(0, 2)), max_failures=draw(hst.sampled_from((None, 1, 2))),
    )
    return Scenario(name="generated", model=model, initial=tuple(initial), timeline=(TimedEvent(0, ActionChange(actions[0])),), checker=bounds)


#: examples of the generated-model comparison (CI: 40; DESMON_TABLE_EXAMPLES=300 for a longer run)
EXAMPLES = int(os.environ.get("DESMON_TABLE_EXAMPLES", "40"))


@settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    generated_scenarios(),
    hst.sampled_from(["desmon", "paper", "desmon-keep-fallback", "make-before-break", "no-recheck", "capacity-blind", "stale-errors"]),
    hst.booleans(),
    hst.sampled_from([60, 400, 1500]),
)
def test_table_engine_equals_direct_engine_on_generated_models(scenario, deployer, keep_going, cap):
    d, t, _r = _both(scenario, MUTANTS.get(deployer, deployer), keep_going=keep_going, max_states=cap)
    assert t == d


def _follow(trees, node: int, d: int) -> int:  # type: ignore[no-untyped-def]
    """The node the branch for digit ``d`` leads to from one-platform check ``node``, then on
    through every check of the same platform that already has a branch for ``d``."""
    p = int(trees.node_p0.a[node])
    child = int(trees.digit_kids.a[int(trees.digit_base.a[node]) + d])
    while child >= 0:
        cb = int(trees.digit_base.a[child])
        if cb < 0 or int(trees.node_p0.a[child]) != p or int(trees.digit_kids.a[cb + d]) < 0:
            break
        child = int(trees.digit_kids.a[cb + d])
    return child


def _the_walk_codes_are_the_shortcuts(trees) -> None:  # type: ignore[no-untyped-def]
    """Each node's walk code says what it is (a leaf and which, a one-platform check with its
    digit table and platform, another check), and each shortcut's code is its target's."""
    for node in range(trees.node_leaf.n):
        leaf, db = int(trees.node_leaf.a[node]), int(trees.digit_base.a[node])
        want = LEAF | leaf if leaf >= 0 else (db << trees.code_bits | int(trees.node_p0.a[node]) if db >= 0 else WIDE | node)
        assert int(trees.node_code.a[node]) == want, node
        if db >= 0:
            assert int(trees.digit_node.a[db]) == node
    n = trees.digit_kids.n
    jump = trees.digit_jump.a[:n]
    assert (trees.jump_code.a[:n] == np.where(jump >= 0, trees.node_code.a[jump], -1)).all()
    assert (jump >= 0).any()


@pytest.mark.parametrize("name", ["fallbacks", "robot_day", "memory_pressure"])
def test_the_walks_shortcuts_land_where_the_same_platforms_branches_lead(name):
    # a check that asks about the platform its parent branched on is answered by the same
    # digit: the walk takes both branches in one step. Every shortcut, after a whole search
    # has grown the trees run by run, must land exactly where following the branches lands
    checker = Checker(load_scenario(SCENARIOS / f"{name}.py"))
    checker.run(engine="table", max_states=20_000)
    trees = checker.explored._e.trees  # the table engine's decision trees
    R = trees.tables.env.R
    checked = skipped = 0
    for node in range(trees.node_leaf.n):
        db = int(trees.digit_base.a[node])
        if db < 0:
            continue
        for d in range(R[int(trees.node_p0.a[node])]):
            jump = int(trees.digit_jump.a[db + d])
            assert jump == _follow(trees, node, d), (node, d)
            checked += 1
            skipped += jump != int(trees.digit_kids.a[db + d])
    assert checked > 100 and skipped > 0  # (the scenario has such repeated checks)
    _the_walk_codes_are_the_shortcuts(trees)
    # platforms with many digits recompute them with numpy: the same shortcuts, children first
    python_made, python_codes = trees.digit_jump.a.copy(), trees.jump_code.a.copy()
    n = trees.digit_kids.n  # (the rows in use)
    trees.digit_jump.a[:n] = trees.digit_kids.a[:n]  # (each shortcut its branch, then the skips)
    kids = trees.digit_kids.a[:n]
    trees.jump_code.a[:n] = np.where(kids >= 0, trees.node_code.a[kids], -1)
    trees.small_digits = 0
    for node in range(trees.node_leaf.n - 1, -1, -1):  # (a child is numbered after its parent)
        db = int(trees.digit_base.a[node])
        if db >= 0:
            p = int(trees.node_p0.a[node])
            for kid in set(trees.digit_kids.a[db: db + R[p]].tolist()):
                if kid >= 0 and int(trees.digit_base.a[kid]) >= 0 and int(trees.node_p0.a[kid]) == p:
                    trees._rejump(node, kid)
    assert (trees.digit_jump.a[: trees.digit_kids.n] == python_made[: trees.digit_kids.n]).all()
    assert (trees.jump_code.a[: trees.digit_kids.n] == python_codes[: trees.digit_kids.n]).all()


@settings(max_examples=200, deadline=None)
@given(hst.lists(hst.integers(0, 12), max_size=60), hst.integers(0, 1 << 40))
def test_firsts_are_the_first_occurrences_of_each_value_in_order(small, offset):
    # the batch's candidate new states: the first unit reaching each code (np.unique's index)
    from desmon.verify.arrays import firsts

    values = np.array([offset + 97 * v for v in small], dtype=np.int64)
    want = np.sort(np.unique(values, return_index=True)[1]) if len(values) else np.zeros(0, dtype=np.int64)
    got = firsts(values)
    assert got.tolist() == want.tolist() and got.dtype == np.int64


def test_observations_that_conflict_hand_the_search_to_the_direct_engine_under_auto_and_stop_table(monkeypatch):
    """Two recorded runs that read the same facts and did otherwise: the deployer is
    nondeterministic, or it learned a fact the table engine did not observe. Under auto the
    direct engine decides (here: HOLDS, with the reason in its note); --engine table stops."""
    from desmon.errors import ObservationConflict
    from desmon.verify.table import TableEngine

    def conflicting(self, *args, **kwargs):  # type: ignore[no-untyped-def]
        raise ObservationConflict("the deployment core reacted differently to states with the same readings")

    monkeypatch.setattr(TableEngine, "run", conflicting)
    sc = load_scenario(str(SCENARIOS / "coffee_handover.py"))
    result = Checker(sc, "desmon").run(max_states=20_000)
    assert result.verdict == "HOLDS" and result.engine == "direct"
    assert "reacted differently to states with the same readings" in result.engine_note
    with pytest.raises(ObservationConflict):
        Checker(sc, "desmon").run(max_states=20_000, engine="table")
