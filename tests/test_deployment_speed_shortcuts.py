"""The shortcuts on the deployment side answer exactly what the
long way answers.

Each test fails if its shortcut is wrong: the live graph's adjacency other than a
replay of the change log gives, a states tuple handed out for
other states, guard watchers called in another order than a relay calls them, a Control
refusal kept past a device failure or a specification change, an invariant's fast answer
that differs from its full one.
"""

from __future__ import annotations

import pytest
from conftest import force_robot_world

from desmon.deployment.control import ControlRules
from desmon.deployment.guard import Guard
from desmon.deployment.invariants import INVARIANTS, make_view
from desmon.deployment.ports import RaiseError, Start, Stop, relay
from desmon.deployment.validity import PlatformMemoChecks, loop_validity
from desmon.model.requirements import DeploymentSpec
from desmon.model.system import PlatformState
from desmon.repository import RepositoryQuery, set_device_working, set_load
from desmon.repository.facts import record_start, record_stop


@pytest.fixture
def world():  # type: ignore[no-untyped-def]
    return force_robot_world(other=True)


def _adjacency(g):  # type: ignore[no-untyped-def]
    """Every side of a MultiDiGraph's adjacency, in its orders (nodes, neighbours, keys)."""
    succ = [(u, [(v, list(kd.items())) for v, kd in nbrs.items()]) for u, nbrs in g._succ.items()]
    pred = [(u, [(v, list(kd.items())) for v, kd in nbrs.items()]) for u, nbrs in g._pred.items()]
    return list(g.nodes(data=True)), succ, pred


# ---------------------------------------------------------------------------- the live graph
def test_the_live_graph_is_what_the_change_log_replays_to(world):
    _model, repo = world
    dep, other, pc1, pc2 = "Deployment:force", "Deployment:other", "Platform:pc1", "Platform:pc2"
    # two edges between one pair (the second key keeps the pair's key dict), relabels,
    # removals that empty a pair and re-add it (it then comes last among the neighbours)
    record_start(repo, "force", "pc1")
    repo.add_edge(dep, pc1, "EXTRA", key="EXTRA#1", note=1)
    record_start(repo, "other", "pc2")
    record_stop(repo, "force", "pc1")
    record_start(repo, "force", "pc2")
    repo.remove_edge(dep, pc1, "EXTRA#1")
    record_stop(repo, "force", "pc2")
    record_start(repo, "force", "pc1")
    record_stop(repo, "other", "pc2")
    set_device_working(repo, "ft", False)
    set_device_working(repo, "ft", True)
    live, replayed = repo.graph, repo.snapshot()
    assert _adjacency(live) == _adjacency(replayed)
    assert repo.successors(dep, "DEPLOYED_ON") == [pc1] and repo.predecessors(pc2, "DEPLOYED_ON") == []
    assert len(repo.labelled("DEPLOYMENT_HISTORY")) == 3 and sorted(repo.successors(other, "DEPLOYMENT_HISTORY")) == [pc2]


# ---------------------------------------------------------------------------- the states tuple
def test_the_states_tuple_is_handed_out_again_only_for_the_same_states(world):
    _model, repo = world
    q = RepositoryQuery(repo)
    first = q.platform_states()
    set_load(repo, "pc1", "memory", 100.0)
    loaded = q.platform_states()
    assert loaded is not first and loaded[0].load == (("memory", 100.0),)
    set_load(repo, "pc1", "memory", 0.0)
    back = q.platform_states()
    assert back is first and all(a is b for a, b in zip(back, first))
    set_device_working(repo, "ft", False)
    failed = q.platform_states()
    assert failed is not first and [d.name for d in failed[0].devices] == ["ft2"]
    assert failed == (q.platform_state("pc1"), q.platform_state("pc2"))


# ---------------------------------------------------------------------------- guard watchers
def _reaction(log):  # type: ignore[no-untyped-def]
    def react():  # type: ignore[no-untyped-def]
        ok = yield Start("force", "pc1")
        log.append(("got", ok))
        yield RaiseError("deployment_failed", "force", "pc1")
        ok = yield Stop("other", "pc2")
        log.append(("got", ok))
    return react


def _drive(reaction, outcomes):  # type: ignore[no-untyped-def]
    outcome = None
    try:
        while True:
            cmd = reaction.send(outcome)
            outcome = outcomes.get(type(cmd))
    except StopIteration:
        pass


@pytest.mark.parametrize("outcomes", [{Start: True, Stop: True}, {Start: False, Stop: False}])
def test_guard_watchers_see_what_a_relay_sees(outcomes):
    names = (frozenset({"force", "other"}), frozenset({"pc1", "pc2"}))
    seen: dict[str, list] = {"hooks": [], "relay": []}
    for way in seen:
        log = seen[way]

        def before(cmd, log=log):  # type: ignore[no-untyped-def]
            log.append(("before", cmd))

        def after(cmd, outcome, log=log):  # type: ignore[no-untyped-def]
            log.append(("after", cmd, outcome))

        make = _reaction(log)
        if way == "hooks":
            reaction = Guard().guarded("d", make, None, *names, lambda: "", before, after)
        else:
            reaction = relay(Guard().guarded("d", make, None, *names, lambda: ""), before=before, after=after)
        _drive(reaction, outcomes)
    assert seen["hooks"] == seen["relay"]
    assert [e[0] for e in seen["hooks"]][:3] == ["before", "after", "got"]


# ---------------------------------------------------------------------------- validity without preferences
def test_memo_validity_without_preferences_is_the_loops(world):
    model, repo = world
    q = RepositoryQuery(repo)
    checks = PlatformMemoChecks()
    record_start(repo, "other", "pc2")
    for _step in range(2):
        states = q.platform_states()
        for spec in model.specs:
            for reasons in (False, True):
                got = checks.compute(spec.requirements, states, spec.graph, reasons)
                assert got == loop_validity(spec.requirements, states, spec.graph, reasons)
                assert repr(got) == repr(loop_validity(spec.requirements, states, spec.graph, reasons))
        set_device_working(repo, "ft", False)
        set_device_working(repo, "ft2", False)


# ---------------------------------------------------------------------------- the Control refusal
def test_a_kept_refusal_follows_the_facts_and_the_spec():
    from desmon.loader import load_scenario
    from desmon.sim.engine import SimWorld

    w = SimWorld(load_scenario("scenarios/robot_day.py"), seed=0, signals=False, until=1.0)
    infra, facts = w.infra, w.facts
    assert type(infra.rules) is ControlRules
    pairs = [(g.name, p.name) for g in w.model.graphs for p in w.model.platforms]

    def fresh(g: str, p: str) -> str:
        return infra.rules.start_refusal(g, p, facts.state) or ""

    assert all(infra._rules_refusal(g, p) == fresh(g, p) for g, p in pairs)
    before = {pair: infra._rules_refusal(*pair) for pair in pairs}
    for d in w.model.devices:  # every device fails: the kept answers must not outlive it
        facts.dev_ok[d.name] = False
    assert all(infra._rules_refusal(g, p) == fresh(g, p) for g, p in pairs)
    assert any(infra._rules_refusal(*pair) != before[pair] for pair in pairs)
    for d in w.model.devices:
        facts.dev_ok[d.name] = True
    assert {pair: infra._rules_refusal(*pair) for pair in pairs} == before
    # another specification object (a requirement change): asked again. With every device
    # failed the declared specifications are refused; one that reads and needs nothing is not
    for d in w.model.devices:
        facts.dev_ok[d.name] = False
    refused = {pair: infra._rules_refusal(*pair) for pair in pairs}
    graph = next(g for g, p in pairs if refused[(g, p)])
    spec = w.query.deployment_information(graph)
    changed = DeploymentSpec(graph, (), spec.fixed_platform, spec.rebalance, ())
    infra.rules.spec_of = lambda g: changed if g == graph else w.query.deployment_information(g)
    assert all(infra._rules_refusal(g, p) == fresh(g, p) for g, p in pairs)
    assert any(infra._rules_refusal(g, p) != refused[(g, p)] for g, p in pairs if g == graph)


# ---------------------------------------------------------------------------- invariants' fast answers
def _full_single_instance(v):  # type: ignore[no-untyped-def]
    where: dict[str, list[str]] = {}
    for g, p in v.deployments:
        where.setdefault(g, []).append(p)
    for g, ps in sorted(where.items()):
        if len(ps) > 1:
            return f"{g} is active on {len(ps)} platforms: {', '.join(ps)}"
    return None


def test_invariants_fast_answers_are_the_full_ones(world):
    model, _repo = world
    pc1, pc2 = model.platforms
    use = (("memory", 300.0),)
    specs = model.specs
    cases = [
        (PlatformState(pc1), PlatformState(pc2)),
        (PlatformState(pc1, deployed=(("other", use),)), PlatformState(pc2, deployed=(("other", use),))),
        (PlatformState(pc1, deployed=(("force", (("memory", 50.0),)), ("other", use))), PlatformState(pc2)),
    ]
    single, overcommit, fixed = INVARIANTS["single-instance"], INVARIANTS["no-overcommit"], INVARIANTS["fixed"]
    for states in cases:
        v = make_view(states, specs, frozenset(), ())
        assert single.check(v) == _full_single_instance(v)
    assert single.check(make_view(cases[1], specs, frozenset(), ())) == "other is active on 2 platforms: pc1, pc2"
    assert overcommit.check(make_view(cases[1], specs, frozenset(), ())) == (
        "pc2: deployments consume 300 memory (other 300) but the capacity is 256"
    )
    assert overcommit.check(make_view(cases[0], specs, frozenset(), ())) is None
    # fixed: a tuple without a fixed platform, then one with: each answered for itself
    v = make_view(cases[1], specs, frozenset(), ())
    assert fixed.check(v) is None
    fixed_specs = tuple(DeploymentSpec(s.graph, s.requirements, "pc1", s.rebalance, s.reads) for s in specs)
    assert fixed.check(make_view(cases[1], fixed_specs, frozenset(), ())) == "other is fixed to pc1 (EXECUTABLE_ON) but runs on pc2"
    assert fixed.check(make_view(cases[1], list(specs), frozenset(), ())) is None  # type: ignore[arg-type]
    assert fixed.check(make_view(cases[1], list(fixed_specs), frozenset(), ())) is not None  # type: ignore[arg-type]
    assert fixed.check(v) is None


# ---------------------------------------------------------------------------- platform state parts
def _facts(states):  # type: ignore[no-untyped-def]
    """Each state's facts with the types of its amounts (1 and 1.0 are other facts)."""
    return [
        (s.name, s.up, [d.name for d in s.devices], [(r, a, type(a)) for r, a in s.load],
         [(g, [(r, a, type(a)) for r, a in use]) for g, use in s.deployed])
        for s in states
    ]


def test_kept_loads_and_consumptions_follow_the_repository(world):
    from desmon.model.events import RequirementChange
    from desmon.model.requirements import Capacity
    from desmon.repository.facts import change_requirements

    _model, repo = world
    q = RepositoryQuery(repo)

    def same_as_fresh():  # type: ignore[no-untyped-def]
        kept = q.platform_states()
        assert _facts(kept) == _facts(RepositoryQuery(repo).platform_states())
        return kept

    same_as_fresh()
    set_load(repo, "pc1", "memory", 100.0)
    same_as_fresh()
    record_start(repo, "force", "pc1")  # the platform is re-read, its load dict is the same
    same_as_fresh()
    set_load(repo, "pc1", "memory", 7)  # an int: another fact than 7.0
    same_as_fresh()
    set_load(repo, "pc1", "memory", 7.0)
    same_as_fresh()
    change_requirements(repo, RequirementChange("force", add=(Capacity("memory", 80),), remove=(Capacity("memory", 50),)))
    states = same_as_fresh()
    assert states[0].deployed == (("force", (("memory", 80.0),)),)
    record_start(repo, "other", "pc1")
    record_stop(repo, "force", "pc1")
    same_as_fresh()


# ---------------------------------------------------------------------------- failure texts and remote inputs
def test_kept_failure_texts_are_each_questions_own(world):
    from desmon.deployment.validity import platform_failures
    from desmon.model.requirements import Capacity

    _model, repo = world
    checks = PlatformMemoChecks()
    states = RepositoryQuery(repo).platform_states()
    questions = [(Capacity("memory", 600),), (Capacity("memory", 900), Capacity("memory", 700)), (Capacity("memory", 600),)]
    for _round in range(2):
        for reqs in questions:
            for first_only in (True, False):
                want = [platform_failures(reqs, s, "force", first_only) for s in states]
                assert checks.each_platform(reqs, states, "force", first_only) == want
                assert [checks.platform(reqs, s, "force", first_only) for s in states] == want
                got = checks.compute(reqs, states, "force", not first_only)
                assert got == loop_validity(reqs, states, "force", not first_only)


def test_deployment_valid_reads_remote_inputs_only_where_the_platform_hosts_none(world):
    from desmon.deployment.validity import _lookup, check_platform, deployment_valid, input_failures

    model, repo = world
    force = next(s for s in model.specs if s.graph == "force")
    # no requirement of its own: on pc2 only the remote half (pc1's force sensors) can fail
    spec = DeploymentSpec("force", (), None, None, force.reads)
    q = RepositoryQuery(repo)
    remote = []
    for step in ("ok", "ft fails", "ft2 fails", "pc1 loaded"):
        if step == "ft fails":
            set_device_working(repo, "ft", False)
        elif step == "ft2 fails":
            set_device_working(repo, "ft2", False)
        elif step == "pc1 loaded":
            set_load(repo, "pc1", "memory", 500.0)
        states = q.platform_states()
        for state in states:
            fails = check_platform(spec.requirements + spec.reads, state, spec.graph)
            want = fails or input_failures(spec.reads, state.platform.name, _lookup(states), spec.graph)
            assert deployment_valid(spec, state, states) == want
            remote += [f.platform for f in want if f.platform == "pc2"]
    assert remote == ["pc2", "pc2"]  # the remote half failed once both of pc1's sensors failed


# ---------------------------------------------------------------------------- exposure checks
def test_exposure_asks_valid_times_once_per_switch_as_graph_by_graph():
    import random

    from desmon.sim.metrics import Exposure

    rng = random.Random(7)
    times: dict[str, float] = {}
    asked: list[dict[str, float]] = []

    def valid_times():  # type: ignore[no-untyped-def]
        asked.append(dict(times))
        return dict(times)

    events_a: list[tuple] = []
    events_b: list[tuple] = []
    fast = Exposure(lambda g: times.get(g, float("inf")), lambda *a: events_a.append(a), valid_times)
    slow = Exposure(lambda g: times.get(g, float("inf")), lambda *a: events_b.append(a))
    slots_of = [(), (("a",),), (("a", "b"), ("c",)), (("b",), ("c",))]
    now = 0.0
    for _ in range(400):
        now += rng.choice([0.0, 0.5, 1.0, 2.0])
        g = rng.choice("abc")
        if rng.random() < 0.5:
            times[g] = now + rng.choice([0.0, 0.7, 3.0])
        else:
            times.pop(g, None)
        if rng.random() < 0.3:  # else the switch finds time to account since the last change
            for ex in (fast, slow):
                ex.advance(now)
                ex.check(now)
        now += rng.choice([0.0, 0.5])
        ctx = rng.choice(["x", "y"])
        slots = rng.choice(slots_of)
        for ex in (fast, slow):
            ex.set_wanted(now, slots, ctx)
        assert (fast.exposure, fast.risky, fast.blind, fast.intervals) == (slow.exposure, slow.risky, slow.blind, slow.intervals)
    assert events_a == events_b and events_a
    assert len(asked) < 2 * 400  # the switches asked once where the advance and the check both needed it


@pytest.mark.parametrize("signals", [False, True])
def test_a_start_checks_the_exposure_once_as_twice(monkeypatch, signals):
    from desmon.loader import load_scenario
    from desmon.sim.engine import SimWorld
    from desmon.sim.infrastructure import Infrastructure

    def records():  # type: ignore[no-untyped-def]
        world = SimWorld(load_scenario("scenarios/robot_day.py"), seed=3, signals=signals, until=1800.0)
        res = world.run()
        return res.trace.records, res.metrics

    short = records()
    flush = Infrastructure.flush_ready

    def long_way(self):  # type: ignore[no-untyped-def]
        flush(self)
        return False  # every caller checks the exposure again

    monkeypatch.setattr(Infrastructure, "flush_ready", long_way)
    assert records() == short
