"""The table engine on preferences, rebalancing, requirement changes and joining platforms:
the direct engine's result without falling back to it."""

from __future__ import annotations

import inspect
import os
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as hst

from desmon.cli import main
from desmon.deployment import validity
from desmon.deployment.deployer import DESMON, Deployer
from desmon.deployment.ports import NO_ACCEPTABLE_PLATFORMS, RaiseError
from desmon.loader import load_scenario
from desmon.model import GRASP, HOLD, MOVE_BASE, RELEASE, RobotBuilder
from desmon.model.events import ActionChange, LoadChange, RequirementChange
from desmon.model.requirements import Capacity, Preference
from desmon.model.scenario import Scenario, TimedEvent
from desmon.verify import Bounds, Checker
from desmon.verify.mutants import MUTANTS
from test_verify_table import _both  # everything a user sees of a result, engine against engine

SCENARIOS = Path(__file__).resolve().parent.parent / "scenarios"


# -- deployers that use what preferences add to a Validity ------------------------------


def _score_reader(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    # decides on the scores, the second-best platform and the breakdown's text
    for g in sorted({g for slot in slots for g in slot}):
        spec = q.deployment_information(g)
        if spec is None:
            continue
        v = validity.validity_for(q, spec)
        if v.scores and v.scores[-1] < 0.3 and len(v.acceptable) > 1:
            yield RaiseError(NO_ACCEPTABLE_PLATFORMS, g, v.acceptable[1], "low score")
        elif "score" in v.explain() and v.gain(v.acceptable[-1]) > 0.5:
            yield RaiseError(NO_ACCEPTABLE_PLATFORMS, g, None, "wide spread")
    yield from DESMON.react(q, slots, changed, context_changed)


SCORE_READER = Deployer("score-reader", "decides on scores, ranks and the breakdown", _score_reader)


def _restless(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    # rebalances in every reaction, as if the context had changed (not only when the
    # platforms concerned changed): after a failed move it would move again with nothing
    # changed (the state half of no-flapping)
    yield from DESMON.react(q, slots, changed, True)


RESTLESS = Deployer("restless", "rebalances in every reaction", _restless)
DEPLOYERS = {"score-reader": SCORE_READER, "restless": RESTLESS, **MUTANTS}


# -- generated models ---------------------------------------------------------------

ACTIONS = (HOLD, GRASP, MOVE_BASE, RELEASE)
GRAPHS = ("force", "tactile", "combined")
WEIGHTS = (0.25, 0.5, 1.0, 2.0)


def _preference(draw, graph: str, graphs: list[str], vendors: list[str]) -> Preference:  # type: ignore[no-untyped-def]
    others = [h for h in graphs if h != graph]
    kinds = ("vendor", "attribute", "most_free", "least_loaded", "spread") + (("colocate",) if others else ())
    kind = draw(hst.sampled_from(kinds))
    if kind == "vendor":
        args: tuple[str, ...] = ("force_sensor", draw(hst.sampled_from(vendors)))
    elif kind == "attribute":
        args = ("site", draw(hst.sampled_from(("a", "b"))))
    elif kind in ("most_free", "least_loaded"):
        args = ("memory",)
    elif kind == "colocate":
        args = tuple(draw(hst.lists(hst.sampled_from(others), min_size=1, max_size=2, unique=True)))
    else:
        args = ()
    return Preference(kind, args, draw(hst.sampled_from(WEIGHTS)))


@hst.composite
def preference_scenarios(draw):  # type: ignore[no-untyped-def]
    """2-4 platforms (the last on demand, joining and leaving), 1-3 graphs with random
    preferences and rebalance thresholds, 1-2 requirement changes, loads, failing devices."""
    n = draw(hst.integers(2, 4))
    r = RobotBuilder("pref")
    plats, devices, vendors = [f"pc{i}" for i in range(n - 1)] + ["edge"], [], []
    for i, p in enumerate(plats):
        site = "a" if i == 0 else "b" if p == "edge" else draw(hst.sampled_from(("a", "b")))
        pb = r.platform(
            p, memory=draw(hst.sampled_from((256, 400, 512, 1024))), preference=draw(hst.integers(0, 1)),
            attributes={"site": site}, on_demand=p == "edge",
        )
        if p != "edge" and (i == 0 or draw(hst.booleans())):
            vendor = draw(hst.sampled_from(("kuka", "ati")))
            pb.device(f"wrench{i}", kind="force_sensor", vendor=vendor)
            devices.append(f"wrench{i}")
            vendors.append(vendor)
    graphs = list(GRAPHS[: draw(hst.integers(1, 3))])
    for g in graphs:
        with r.rpsl.perception_graph(g) as gb:
            gb.sensor("s", reads="force_sensor")
            gb.processing("p", inputs=["s"])
    declared: dict[str, float] = {}
    for g in graphs:
        spec = r.depsl.deployment_specification(g)
        if g == "force":
            spec.add_constraint("attribute", "platform_has", "force_sensor")
        declared[g] = draw(hst.sampled_from((100, 150, 250)))
        spec.add_constraint("capacity", "memory", declared[g])
        prefs = draw(hst.integers(0, 3))
        seen: set[tuple] = set()
        for _ in range(prefs):
            pref = _preference(draw, g, graphs, vendors)
            if (pref.kind, pref.args) not in seen:  # the DSL refuses the same preference twice
                seen.add((pref.kind, pref.args))
                spec.prefer(pref.kind, *pref.args, weight=pref.weight)
        rebalance = draw(hst.sampled_from((None, 0.0, 0.1, 0.3, 0.6)))
        if rebalance is not None and prefs:
            spec.rebalance(rebalance)
    bodies = hst.one_of(
        hst.lists(hst.sampled_from(graphs), min_size=1, max_size=2, unique=True),
        hst.lists(hst.sampled_from(graphs), min_size=1, max_size=3, unique=True).map(lambda gs: [tuple(gs)]),
    )
    r.rules({a: draw(bodies) for a in ACTIONS})
    changes = []
    for _ in range(draw(hst.integers(1, 2))):
        g = draw(hst.sampled_from(graphs))
        if draw(hst.booleans()):
            amount = draw(hst.sampled_from((50, 200, 350)))
            changes.append(RequirementChange(g, add=(Capacity("memory", amount),), remove=(Capacity("memory", declared[g]),)))
        else:
            changes.append(RequirementChange(g, add=(_preference(draw, g, graphs, vendors),)))
    changes = list(dict.fromkeys(changes))
    actions = draw(hst.lists(hst.sampled_from(ACTIONS), min_size=2, max_size=3, unique=True))
    loaded = draw(hst.lists(hst.sampled_from(plats), max_size=2, unique=True))
    bounds = Bounds(
        actions=tuple(actions), initial_action=actions[0],
        devices=tuple(draw(hst.lists(hst.sampled_from(devices), max_size=2, unique=True))),
        repair=draw(hst.booleans()),
        platforms=tuple(draw(hst.lists(hst.sampled_from(plats[:-1]), max_size=1, unique=True))),
        loads={p: (0, 100, 300)[: draw(hst.integers(2, 3))] for p in loaded},
        joins=("edge",), requirement_changes=tuple(changes),
        start_failures=draw(hst.integers(0, 1)), max_failures=draw(hst.sampled_from((None, 1))),
    )
    return Scenario(
        name="generated_prefs", model=r.build(), initial=tuple(LoadChange(p, 0) for p in loaded),
        timeline=(TimedEvent(0, ActionChange(actions[0])),), checker=bounds,
    )


#: examples of the generated-model comparison (CI: 25; DESMON_TABLE14_EXAMPLES=300 for a longer run)
EXAMPLES = int(os.environ.get("DESMON_TABLE14_EXAMPLES", "25"))
DEPLOYER_NAMES = ["desmon", "paper", "desmon-keep-fallback", "no-hysteresis", "restless", "score-reader", "make-before-break", "stale-errors"]


def _compare(scenario, deployer, keep_going, cap):  # type: ignore[no-untyped-def]
    d, t, _r = _both(scenario, DEPLOYERS.get(deployer, deployer), keep_going=keep_going, max_states=cap)
    assert t == d


@settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(preference_scenarios(), hst.sampled_from(DEPLOYER_NAMES), hst.booleans(), hst.sampled_from([60, 400, 1500]))
def test_table_engine_equals_direct_engine_on_models_with_preferences_joins_and_requirement_changes(scenario, deployer, keep_going, cap):
    _compare(scenario, deployer, keep_going, cap)


@pytest.mark.slow
@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(preference_scenarios(), hst.sampled_from(DEPLOYER_NAMES), hst.booleans(), hst.sampled_from([400, 3000]))
def test_table_engine_equals_direct_engine_on_many_models_with_preferences_joins_and_requirement_changes(scenario, deployer, keep_going, cap):
    _compare(scenario, deployer, keep_going, cap)


# -- cloud_offload: the shipped scenario with all four ----------------------------------


def test_cloud_offload_runs_on_the_table_engine_with_the_direct_engines_result():
    scenario = load_scenario(SCENARIOS / "cloud_offload.py")
    for kw in ({}, {"keep_going": True}, {"max_depth": 3}):
        d, t, r = _both(scenario, "desmon", **kw)
        assert t == d
        assert r.engine_note == "" and r.records < r.transitions
    auto = Checker(scenario).run()
    assert auto.engine == "table" and auto.verdict == "HOLDS"


def test_engine_table_verifies_cloud_offload_from_the_command_line(capsys):
    assert main(["verify", str(SCENARIOS / "cloud_offload.py"), "--engine", "table", "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "verdict: HOLDS" in out and "engine: table" in out


# -- no-hysteresis: the transition half of no-flapping --------------------------------


def _two_pcs(rebalance: float, start_failures: int = 0) -> Scenario:
    """One graph preferring the most free memory on two equal PCs; pc0's load steps to
    250 MB, so pc1 beats pc0 by 0.25."""
    r = RobotBuilder("two_pcs")
    r.platform("pc0", memory=1000).device("wrench", kind="force_sensor")
    r.platform("pc1", memory=1000)
    with r.rpsl.perception_graph("combined") as gb:
        gb.sensor("s", reads="force_sensor")
        gb.processing("p", inputs=["s"])
    r.depsl.deployment_specification("combined").add_constraint("capacity", "memory", 100).prefer("most_free", "memory").rebalance(rebalance)
    r.rules({HOLD: "combined", GRASP: "combined"})
    return Scenario(
        name="two_pcs", model=r.build(), initial=(LoadChange("pc0", 0),), timeline=(TimedEvent(0, ActionChange(HOLD)),),
        checker=Bounds(actions=(HOLD, GRASP), loads={"pc0": (0, 250)}, start_failures=start_failures),
    )


def test_the_no_hysteresis_mutant_is_caught_by_no_flapping_with_the_same_counterexample_on_both_engines():
    scenario = _two_pcs(0.5)
    for kw in ({}, {"keep_going": True}):
        d, t, r = _both(scenario, MUTANTS["no-hysteresis"], **kw)
        assert t == d
        assert r.verdict == "VIOLATED" and r.counterexamples[0].invariant == "no-flapping"
        assert "not above its min_gain 0.5" in r.counterexamples[0].message
    # the corrected deployer keeps the deployment: a gain of 0.25 is not above 0.5
    assert Checker(scenario).run(engine="table").verdict == "HOLDS"


def test_a_deployer_that_would_move_again_with_nothing_changed_violates_no_flapping_on_both_engines():
    # the move to pc1 fails, the detector is started on pc0 again, where it runs validly
    # but scores 0.25 below pc1: every later reaction would retry the move
    d, t, r = _both(_two_pcs(0.1, start_failures=1), RESTLESS)
    assert t == d
    assert r.verdict == "VIOLATED" and r.counterexamples[0].invariant == "no-flapping"
    assert "with nothing changed the deployer would move combined off pc0" in r.counterexamples[0].message
    # the corrected deployer moves only in answer to a change of the platforms concerned
    assert Checker(_two_pcs(0.1, start_failures=1)).run(engine="table").verdict == "HOLDS"


def test_a_gain_above_min_gain_moves_the_deployment_on_both_engines():
    d, t, r = _both(_two_pcs(0.1), "desmon", keep_going=True)
    assert t == d
    assert r.verdict == "HOLDS" and r.branches["stop ok"] > 0  # it moved, and that is no flapping


def test_verify_reports_no_hysteresis_violating_no_flapping_from_the_command_line(tmp_path, capsys):
    path = tmp_path / "two_pcs.py"  # a scenario file with the model above
    path.write_text(
        "from desmon.model import GRASP, HOLD, RobotBuilder\n"
        "from desmon.model.events import ActionChange, LoadChange\n"
        "from desmon.model.scenario import Scenario, TimedEvent\n"
        "from desmon.verify import Bounds\n\n"
        f"{inspect.getsource(_two_pcs)}\n"
        "scenario = _two_pcs(0.5)\n"
    )
    code = main(["verify", str(path), "--deployer", "mutant:no-hysteresis", "--no-progress"])
    out = capsys.readouterr().out
    assert code == 1 and "VIOLATED" in out and "no-flapping" in out


# -- the encoding's limits ---------------------------------------------------------------


def test_requirement_changes_reaching_too_many_variants_run_on_the_direct_engine():
    scenario = _two_pcs(0.5)
    changes = tuple(RequirementChange("combined", add=(Preference("spread", (), w),)) for w in (0.25, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 4.5, 5.0))
    b = scenario.checker
    crowded = Scenario(
        name="crowded", model=scenario.model, initial=scenario.initial, timeline=scenario.timeline,
        checker=Bounds(actions=b.actions, loads=b.loads, requirement_changes=changes),
    )
    auto = Checker(crowded).run(max_states=50)
    assert auto.engine == "direct" and "variants" in auto.engine_note


def test_the_table_engine_enables_exactly_the_alphabets_joins_leaves_and_requirement_changes_in_its_order():
    import numpy as np

    from desmon.verify.environment import enabled_events

    checker = Checker(load_scenario(SCENARIOS / "cloud_offload.py"))
    checker.run(engine="table", keep_going=True)
    engine = checker.explored._e  # the table engine of the run
    states = list(checker.explored)
    tr = engine.events.enabled(np.frombuffer(engine.codes, dtype=np.int64))
    table: list[list] = [[] for _ in states]
    for pos, ev in zip(tr.pos.tolist(), tr.ev.tolist()):
        table[pos].append(engine.events.events[ev])
    assert any(k.specs for k in states) and any("edge" not in k.down for k in states)
    for key, events in zip(states, table):
        assert events == enabled_events(checker.bounds, key), key
