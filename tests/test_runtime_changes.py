"""Requirements that change at run time and on-demand platforms: the deployer
follows a RequirementChange like any fact, an on-demand platform is absent until it
joins, and the SimPy world leases one when nothing else fits."""

from __future__ import annotations

import io

import pytest

from desmon.deployment.validity import validity_for
from desmon.errors import DesmonError, ModelError, ScenarioError
from desmon.loader import load_scenario
from desmon.model import GRASP, HOLD, RobotBuilder
from desmon.model.events import ActionChange, LoadChange, PlatformDown, PlatformJoin, PlatformLeave, PlatformUp, RequirementChange
from desmon.model.requirements import Capacity, Preference
from desmon.model.scenario import Scenario, TimedEvent
from desmon.repository import RepositoryQuery, labels as L
from desmon.repository.store import node_id
from desmon.sim.engine import simulate
from desmon.sim.replay import replay
from desmon.sim.trace import Trace
from desmon.sim.world import Lease, RandomChanges, Step, World

SMALL, BIG, HUGE = Capacity("memory", 100), Capacity("memory", 600), Capacity("memory", 5000)


def robot(*, on_demand: bool = False) -> RobotBuilder:
    """pc1 (512 MB, the force sensor), pc2 (1024 MB) and, on demand, edge (2048 MB)."""
    r = RobotBuilder("r")
    r.platform("pc1", memory=512).device("ft", kind="force_sensor")
    r.platform("pc2", memory=1024)
    if on_demand:
        r.platform("edge", memory=2048, on_demand=True, startup_s=5.0)
    with r.rpsl.perception_graph("A") as g:
        g.sensor("s", reads="force_sensor")
    r.depsl.deployment_specification("A").require(SMALL)
    r.rules({"grasp": ["A"]})
    return r


def timeline(*events) -> tuple[TimedEvent, ...]:
    return tuple(TimedEvent(float(i + 1), ev, f"t{i + 1}") for i, ev in enumerate(events))


def requirements(rep, graph: str = "A"):
    return RepositoryQuery(rep.repo).deployment_information(graph).requirements


# ---------------------------------------------------------------- the deployer follows the change


def test_a_larger_requirement_migrates_the_deployment_stopping_before_starting():
    grow = RequirementChange("A", add=(BIG,), remove=(SMALL,))
    rep = replay(Scenario(name="grow", model=robot().build(), timeline=timeline(ActionChange(GRASP), grow)))
    first, second = rep.steps
    assert first.deployments == (("A", "pc1"),)
    assert second.stimulus.specs_changed == ("A",)
    assert [str(c) for c, _ok in second.commands] == ["stop A on pc1", "start A on pc2"]
    assert second.deployments == (("A", "pc2"),)
    assert rep.violations == []


def test_after_a_change_the_repository_requires_the_new_requirement_and_consumption_follows():
    grow = RequirementChange("A", add=(BIG,), remove=(SMALL,))
    rep = replay(Scenario(name="grow", model=robot().build(), timeline=timeline(ActionChange(GRASP), grow)))
    assert requirements(rep) == (BIG,)
    pc2 = next(s for s in RepositoryQuery(rep.repo).platform_states() if s.name == "pc2")
    assert pc2.used_by("memory") == [("A", 600.0)]
    required = [t for s, t, d in rep.repo.graph.edges(data=True) if d["label"] == L.REQUIRES and s.endswith(":A")]
    assert len(required) == 1


def test_a_requirement_nothing_can_meet_stops_the_deployment_and_raises_an_error():
    grow = RequirementChange("A", add=(HUGE,), remove=(SMALL,))
    rep = replay(Scenario(name="huge", model=robot().build(), timeline=timeline(ActionChange(GRASP), grow)))
    last = rep.steps[-1]
    assert last.deployments == ()
    assert [e.graph for e in last.errors] == ["A"]
    assert "A" in last.standing


def test_a_change_back_lets_the_graph_return():
    grow = RequirementChange("A", add=(HUGE,), remove=(SMALL,))
    shrink = RequirementChange("A", add=(SMALL,), remove=(HUGE,))
    rep = replay(Scenario(name="back", model=robot().build(), timeline=timeline(ActionChange(GRASP), grow, shrink)))
    assert rep.steps[-1].deployments == (("A", "pc1"),)
    assert requirements(rep) == (SMALL,)
    assert rep.steps[-1].standing == frozenset()


def test_a_change_that_leaves_the_deployment_valid_starts_and_stops_nothing():
    tweak = RequirementChange("A", add=(Capacity("memory", 200),), remove=(SMALL,))
    rep = replay(Scenario(name="tweak", model=robot().build(), timeline=timeline(ActionChange(GRASP), tweak)))
    assert [c for c, ok in rep.steps[-1].commands if ok is not None] == []
    assert rep.steps[-1].deployments == (("A", "pc1"),)


def test_adding_a_preference_with_a_change_reorders_where_the_graph_goes_next():
    prefer_pc2 = RequirementChange("A", add=(Preference("most_free", ("memory",)),))
    rep = replay(
        Scenario(
            name="pref",
            model=robot().build(),
            initial=(LoadChange("pc1", 256),),  # pc1 half free, pc2 all free
            timeline=timeline(prefer_pc2, ActionChange(GRASP)),
        )
    )
    assert rep.steps[-1].deployments == (("A", "pc2"),)  # without it: pc1, declared first


# ---------------------------------------------------------------- a change is checked when the scenario is built


def test_a_change_removing_a_requirement_never_declared_is_refused_naming_it():
    bad = RequirementChange("A", remove=(BIG,))
    with pytest.raises(ModelError) as info:
        Scenario(name="bad", model=robot().build(), timeline=timeline(bad))
    message = str(info.value)
    assert "removes Capacity(memory >= 600 MB), which 'A' never has" in message
    assert "\n" not in message


def test_a_change_may_remove_what_another_change_adds():
    add = RequirementChange("A", add=(BIG,), remove=(SMALL,))
    drop = RequirementChange("A", add=(SMALL,), remove=(BIG,))
    rep = replay(Scenario(name="ok", model=robot().build(), timeline=timeline(ActionChange(GRASP), add, drop)))
    assert requirements(rep) == (SMALL,)


def test_an_added_capacity_replaces_the_graphs_capacity_on_its_resource():
    """A graph consumes one amount of a resource: a change that adds a Capacity on it
    replaces the one the graph has then, whether the change removes it or not (in any
    order the checker applies changes, no specification holds two)."""
    bigger = RequirementChange("A", add=(BIG,))
    rep = replay(Scenario(name="ok", model=robot().build(), timeline=timeline(ActionChange(GRASP), bigger)))
    assert requirements(rep) == (BIG,)
    least = Preference("least_loaded", ("memory",))
    assert bigger.apply((SMALL, least), (SMALL, least)) == (least, BIG)


# ---------------------------------------------------------------- one set of requirements, one order


@pytest.mark.parametrize("engine", ["direct", "table"])
def test_the_checker_counts_one_state_per_requirement_set_whatever_order_the_changes_came_in(engine, root):
    """tests/data/requirement_order.py: a Capacity dropped and added back, a Minimum and a
    Maximum added, on a graph whose every requirement set is met: 2 x 2 x 2 sets, 8 states
    (the changes in other orders used to give 21)."""
    from desmon.verify import Checker

    res = Checker(load_scenario(str(root / "tests" / "data" / "requirement_order.py"))).run(engine=engine)
    assert (res.verdict, res.states) == ("HOLDS", 8)


def _order_changes(root):  # type: ignore[no-untyped-def]
    """tests/data/requirement_order.py and its changes by label."""
    sc = load_scenario(str(root / "tests" / "data" / "requirement_order.py"))
    return sc, {c.label: c for c in sc.checker.requirement_changes}


def test_a_change_and_its_reverse_give_back_the_declared_requirements_in_the_world(root):
    sc, by = _order_changes(root)
    cap, attr = sc.model.spec("g").requirements
    (minimum,), (maximum,) = by["a minimum"].add, by["a maximum"].add

    def after(*labels):  # type: ignore[no-untyped-def]
        rep = replay(Scenario(name="order", model=sc.model, timeline=timeline(ActionChange("hold"), *(by[x] for x in labels))))
        node = rep.repo.node_data[node_id(L.DEPLOYMENT, "g")]["spec"].requirements  # what the deployment node holds
        assert requirements(rep, "g") == node  # and what a query reads off its REQUIRES edges
        return node

    assert after("drop the capacity", "the capacity back") == (cap, attr)
    assert after("a minimum", "a maximum") == after("a maximum", "a minimum") == (cap, attr, maximum, minimum)
    assert after("drop the capacity", "a minimum", "the capacity back") == (cap, attr, minimum)


def test_the_explorer_lists_a_deployments_requirements_in_the_order_every_reader_sees(root):
    from desmon.viz.explore import _node_lines

    sc, by = _order_changes(root)
    rep = replay(Scenario(name="order", model=sc.model, timeline=timeline(ActionChange("hold"), by["drop the capacity"], by["the capacity back"])))
    _title, lines, _flags = _node_lines(rep.repo.snapshot(), node_id(L.DEPLOYMENT, "g"))
    assert lines == [r.describe() for r in requirements(rep, "g")] == ["Capacity(memory >= 100 MB)", "Attribute(os = linux)"]


def test_an_attribute_value_written_another_way_is_another_requirement_only_when_it_means_another():
    """A platform's attribute is compared as text: ``gen=1.0`` is not ``1``. Two Attributes
    (and two Selection options) are equal when they mean the same, so a change that swaps
    one for the other is a change in every engine, and ``1`` and ``"1"`` are one requirement."""
    from desmon.model.requirements import Attribute, Option
    from desmon.verify import Checker
    from desmon.verify.bounds import Bounds

    assert Attribute("gen", 1) != Attribute("gen", 1.0) and Attribute("gen", 1) == Attribute("gen", "1")
    assert len({Attribute("gen", 1), Attribute("gen", "1"), Attribute("gen", 1.0)}) == 2
    assert Option.parse("gen=1") == Option(attribute="gen", value=1) != Option(attribute="gen", value=1.0)
    from desmon.model.requirements import declared_order

    (kept,) = declared_order((Attribute("gen", "1"),), (Attribute("gen", 1),))
    assert kept.value == "1"  # the requirement given, in the declared one's place
    one, one_point_zero = Attribute("gen", 1), Attribute("gen", 1.0)
    drop = RequirementChange("g", remove=(one,), label="drop gen=1")
    add = RequirementChange("g", add=(one_point_zero,), label="need gen=1.0")
    r = RobotBuilder("r")
    r.platform("a", memory=512, attributes={"gen": 1}).device("ft", kind="force_sensor")
    r.platform("b", memory=512, attributes={"gen": 1.0}).device("ft2", kind="force_sensor")
    with r.rpsl.perception_graph("g") as g:
        g.sensor("s", reads="force_sensor")
    r.depsl.deployment_specification("g").require(Capacity("memory", 100)).require(one)
    r.rules({HOLD: ["g"]})
    model = r.build()
    rep = replay(Scenario(name="attr", model=model, timeline=timeline(ActionChange(HOLD), drop, add)))
    assert rep.steps[-1].deployments == (("g", "b"),)  # gen=1.0 holds on b only
    sc = Scenario(name="attr", model=model, checker=Bounds(initial_action=HOLD, requirement_changes=(drop, add)))
    direct, table = Checker(sc).run(engine="direct"), Checker(sc).run(engine="table")
    assert direct.verdict == table.verdict == "HOLDS"
    # on a: declared, and without gen; on b: gen=1.0 instead of 1; nowhere (an error): both, which no platform has
    assert direct.states == table.states == 4
    # equal requirements written either way sort alike: one set, one tuple
    gen_one, gen_two = RequirementChange("g", add=(Attribute("gen", "1"),)), RequirementChange("g", add=(Attribute("gen", "2"),))
    start = (Capacity("memory", 100),)
    via_number = gen_two.apply(RequirementChange("g", add=(Attribute("gen", 1),)).apply(start, start), start)
    via_text = gen_two.apply(gen_one.apply(start, start), start)
    assert [r.describe() for r in via_number] == [r.describe() for r in via_text] == ["Capacity(memory >= 100 MB)", "Attribute(gen = 1)", "Attribute(gen = 2)"]


def test_a_specification_built_in_python_refuses_a_requirement_listed_twice_as_the_dsl_does():
    from desmon.model.requirements import Attribute, DeploymentSpec

    with pytest.raises(ModelError, match=r"lists Attribute\(gen = 1\) twice: give it once"):
        DeploymentSpec("g", (Attribute("gen", 1), Capacity("memory", 1), Attribute("gen", "1")))
    with pytest.raises(ModelError, match=r"lists Capacity\(memory >= 1 MB\) twice"):
        DeploymentSpec("g", (Capacity("memory", 1), Capacity("memory", 1)))


def test_a_world_change_may_remove_what_only_an_initial_change_adds_as_the_checker_allows(root):
    from desmon.model.requirements import Minimum
    from desmon.verify import Checker
    from desmon.verify.bounds import Bounds

    sc, by = _order_changes(root)
    add_min = by["a minimum"]
    drop_min = RequirementChange("g", remove=(Minimum("cores", 2),), label="no minimum")
    world = World(task=(Step(HOLD, 20.0),), horizon=20.0, signals=False, changes=(TimedEvent(10.0, drop_min),))
    both = Scenario(name="initial_add", model=sc.model, initial=(add_min,), world=world,
                    checker=Bounds(initial_action=HOLD, requirement_changes=(drop_min,)))
    assert Checker(both).run().verdict == "HOLDS"
    result = simulate(both, "desmon", seed=0)
    assert result.metrics["requirement_changes"] == 1 and not result.violations


def test_a_change_naming_a_graph_without_specification_is_refused():
    with pytest.raises(ModelError, match="names graph 'B' with no deployment specification"):
        Scenario(name="bad", model=robot().build(), timeline=timeline(RequirementChange("B", add=(SMALL,))))


def test_a_change_adding_a_requirement_on_an_unknown_resource_is_refused():
    bad = RequirementChange("A", add=(Capacity("memroy", 10),))
    with pytest.raises(ModelError, match="did you mean 'memory'"):
        Scenario(name="bad", model=robot().build(), timeline=timeline(bad))


@pytest.mark.parametrize(
    "kwargs, fragment",
    [
        ({}, "adds and removes nothing"),
        ({"add": (SMALL,), "remove": (SMALL,)}, "both adds and removes"),
        ({"add": (SMALL, SMALL)}, "adds Capacity(memory >= 100 MB) twice"),
        ({"add": (SMALL, Capacity("memory", 50))}, "adds two Capacity requirements on 'memory': a graph consumes one amount"),
        ({"add": SMALL}, "trailing comma"),
        ({"add": ("capacity",)}, "is not a Quantity"),
        ({"add": (SMALL,), "label": "a\nb"}, "not one line of text"),
        ({"ad": (SMALL,)}, "did you mean 'add'"),
    ],
    ids=["nothing", "both", "twice", "two-amounts", "no-tuple", "not-a-requirement", "label-newline", "keyword-typo"],
)
def test_a_malformed_requirement_change_is_refused_with_one_line(kwargs, fragment):
    with pytest.raises(ModelError) as info:
        RequirementChange("A", **kwargs)
    assert fragment in str(info.value)
    assert "\n" not in str(info.value)


# ---------------------------------------------------------------- on-demand platforms


def test_join_and_leave_are_refused_for_a_platform_that_is_not_on_demand():
    for ev in (PlatformJoin("pc2"), PlatformLeave("pc2")):
        with pytest.raises(ModelError, match="'pc2' is not on demand"):
            Scenario(name="bad", model=robot().build(), timeline=timeline(ev))


def test_up_and_down_are_refused_for_an_on_demand_platform():
    for ev in (PlatformUp("edge"), PlatformDown("edge")):
        with pytest.raises(ModelError, match="'edge' is on demand"):
            Scenario(name="bad", model=robot(on_demand=True).build(), timeline=timeline(ev))


def test_an_on_demand_platform_is_absent_until_it_joins_and_explain_says_so():
    grow = RequirementChange("A", add=(Capacity("memory", 1500),), remove=(SMALL,))
    scenario = Scenario(
        name="join",
        model=robot(on_demand=True).build(),
        timeline=timeline(grow, ActionChange(GRASP), PlatformJoin("edge"), PlatformLeave("edge")),
    )
    rep = replay(scenario)
    _grow, grasp, join, leave = rep.steps
    assert grasp.deployments == () and [e.graph for e in grasp.errors] == ["A"]
    assert join.deployments == (("A", "edge"),)
    assert leave.deployments == ()
    # after the leave the edge is gone again; the reason names it as absent, not as down
    spec = RepositoryQuery(rep.repo).deployment_information("A")
    why = validity_for(RepositoryQuery(rep.repo), spec).explain()
    assert "edge: platform up fails: platform is not there (on demand" in why


def test_startup_s_is_refused_on_a_platform_that_is_not_on_demand():
    with pytest.raises(ModelError, match="startup_s = 5 but is not on_demand"):
        RobotBuilder().platform("pc", memory=512, startup_s=5.0)


def test_on_demand_must_be_true_or_false():
    with pytest.raises(ModelError, match="on_demand = 'yes' is not True or False"):
        RobotBuilder().platform("pc", memory=512, on_demand="yes")


# ---------------------------------------------------------------- the SimPy world


def _world_scenario(**world) -> Scenario:
    base = dict(task=(Step(GRASP, 2.0), Step(HOLD, 8.0)), repeat=True, horizon=600.0, signals=False)
    base.update(world)
    return Scenario(name="rt", model=robot(on_demand=True).build(), world=World(**base))


GROW = RequirementChange("A", add=(BIG,), remove=(SMALL,), label="grow")
SHRINK = RequirementChange("A", add=(SMALL,), remove=(BIG,), label="shrink")


def _trace_text(scenario: Scenario, seed: int) -> str:
    out = io.StringIO()
    simulate(scenario, seed=seed, trace=Trace(out, keep=False))
    return out.getvalue()


def test_random_changes_give_the_same_trace_bytes_for_the_same_seed():
    scenario = _world_scenario(random_changes=RandomChanges((GROW, SHRINK), mean_interval=60.0))
    assert _trace_text(scenario, 7) == _trace_text(scenario, 7)


def test_random_changes_happen_at_other_times_with_another_seed():
    scenario = _world_scenario(random_changes=RandomChanges((GROW, SHRINK), mean_interval=60.0))

    def times(seed: int) -> list[float]:
        return [r["t"] for r in simulate(scenario, seed=seed).trace.of("change")]

    assert times(1) and times(1) != times(2)


def test_scripted_changes_are_applied_and_counted():
    r = simulate(_world_scenario(changes=(TimedEvent(100.0, GROW), TimedEvent(300.0, SHRINK))), seed=0)
    assert r.metrics["requirement_changes"] == 2
    assert [rec["event"] for rec in r.trace.of("change")] == [str(GROW), str(SHRINK)]
    assert r.metrics["violations"] == 0


def test_run_time_metrics_are_absent_from_a_world_that_uses_none_of_them():
    m = simulate(_world_scenario(), seed=0).metrics
    assert not {"requirement_changes", "leases", "leased_s"} & set(m)


def test_the_world_leases_the_on_demand_platform_when_nothing_on_board_fits():
    huge = RequirementChange("A", add=(Capacity("memory", 1500),), remove=(SMALL,))
    scenario = _world_scenario(changes=(TimedEvent(50.0, huge),), lease=Lease(idle_s=30.0))
    r = simulate(scenario, seed=0)
    assert r.metrics["leases"] == 1
    assert r.metrics["leased_s"] > 0
    assert [rec["platform"] for rec in r.trace.of("lease")] == ["edge"]
    assert any(d["command"] == "start" and d["platform"] == "edge" for d in r.trace.of("decision"))


def test_no_lease_for_a_graph_whose_input_no_platform_gives():
    """pc1 holds the only force sensor and is down: the edge server would join for nothing, A
    could not read its input there (the lease had asked the requirements alone, and leased
    it again after each idle time)."""
    from dataclasses import replace

    from desmon.model.events import PlatformDown

    huge = RequirementChange("A", add=(Capacity("memory", 1500),), remove=(SMALL,))
    scenario = _world_scenario(changes=(TimedEvent(50.0, huge),), lease=Lease(idle_s=30.0))
    r = simulate(replace(scenario, initial=(PlatformDown("pc1"),)), seed=0)
    assert r.metrics["leases"] == 0 and r.metrics["leased_s"] == 0
    assert {e.kind for e in r.errors} == {"no_acceptable_platforms"}


def test_without_a_lease_an_on_demand_platform_never_joins():
    huge = RequirementChange("A", add=(Capacity("memory", 1500),), remove=(SMALL,))
    r = simulate(_world_scenario(changes=(TimedEvent(50.0, huge),)), seed=0)
    assert r.metrics["leases"] == 0 and r.metrics["leased_s"] == 0
    assert not any(d["platform"] == "edge" for d in r.trace.of("decision"))


def test_cloud_offload_exposure_with_the_lease_is_never_larger_than_without():
    lowered = 0
    for seed in range(4):
        runs = {}
        for lease in ("True", "False"):
            sc = load_scenario("scenarios/cloud_offload.py", {"hours": "0.3", "lease": lease})
            runs[lease] = simulate(sc, seed=seed, signals=False).metrics
        assert runs["True"]["unmonitored_exposure_s"] <= runs["False"]["unmonitored_exposure_s"]
        assert runs["False"]["leases"] == 0
        lowered += runs["True"]["unmonitored_exposure_s"] < runs["False"]["unmonitored_exposure_s"]
    assert lowered >= 1  # on some seed the torso fills up and the lease pays off


@pytest.mark.parametrize(
    "world, fragment",
    [
        ({"random_changes": RandomChanges((GROW,), mean_interval=60.0), "lease": Lease(platforms=("pc2",))}, "lease names 'pc2', which is no on-demand platform"),
        ({"changes": (TimedEvent(10.0, PlatformJoin("pc2")),)}, "'pc2' is not on demand"),
        ({"changes": (TimedEvent(10.0, PlatformDown("pc2")),)}, "is not a run-time change"),
        ({"random_changes": RandomChanges((RequirementChange("B", add=(SMALL,)),), mean_interval=60.0)}, "names graph 'B' with no deployment specification"),
    ],
    ids=["lease-not-on-demand", "join-not-on-demand", "fault-in-changes", "random-unknown-graph"],
)
def test_a_world_naming_what_the_model_lacks_is_refused(world, fragment):
    with pytest.raises(DesmonError) as info:
        _world_scenario(**world)
    assert fragment in str(info.value)


def test_a_lease_is_refused_when_no_platform_is_on_demand():
    with pytest.raises(ScenarioError, match="no platform is on demand"):
        Scenario(
            name="bad", model=robot().build(),
            world=World(task=(Step(GRASP, 2.0),), horizon=10.0, lease=Lease()),
        )


@pytest.mark.parametrize("interval", [0, -1, float("nan"), float("inf")])
def test_random_changes_need_a_positive_finite_mean_interval(interval):
    with pytest.raises(ScenarioError, match="random changes mean interval"):
        RandomChanges((GROW,), mean_interval=interval)


def test_the_control_rules_refuse_a_start_by_the_requirements_as_they_are_now():
    """A change that adds a device requirement reaches the infrastructure too: the one
    Control semantics reads the current specification, not the declared one."""
    from desmon.deployment.control import repository_refusal
    from desmon.model.requirements import Attribute
    from desmon.repository import Repository
    from desmon.repository.facts import change_requirements, load_model

    model = robot().build()
    repo = Repository()
    load_model(repo, model)
    refuse = repository_refusal(repo, model)
    assert refuse("A", "pc2") is None  # A reads the force sensor on pc1 from anywhere
    change_requirements(repo, RequirementChange("A", add=(Attribute("platform_has", "force_sensor"),)))
    why = refuse("A", "pc2")
    assert why is not None and "platform_has force_sensor" in why
    assert refuse("A", "pc1") is None


def _cloud_with(**bounds):  # type: ignore[no-untyped-def]
    import dataclasses
    import importlib.util

    from desmon.errors import CheckerError  # noqa: F401  (callers expect it)

    spec = importlib.util.spec_from_file_location("cloud_offload_for_test", "scenarios/cloud_offload.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)  # type: ignore[union-attr]
    base = mod.scenario
    initial = base.initial + tuple(bounds.pop("initial", ()))
    return mod, dataclasses.replace(
        base, initial=initial, timeline=(), world=None, checker=dataclasses.replace(base.checker, **bounds)
    )


def test_a_change_in_the_initial_facts_may_be_reversed_by_the_bounds_and_both_engines_agree(monkeypatch, root):
    from desmon.verify import Checker

    monkeypatch.chdir(root)
    mod, _ = _cloud_with()
    _mod, scenario = _cloud_with(initial=(mod.FAST,), requirement_changes=(mod.SLOW,))
    direct = Checker(scenario).run(engine="direct")
    table = Checker(scenario).run(engine="table")
    assert direct.verdict == table.verdict == "HOLDS"
    assert (direct.states, direct.transitions) == (table.states, table.transitions)


def test_bounds_refuse_an_on_demand_platform_among_the_platforms_that_go_down(monkeypatch, root):
    from desmon.errors import CheckerError

    monkeypatch.chdir(root)
    with pytest.raises(CheckerError, match="'edge', which is on demand: it joins and leaves, so list it in joins="):
        _cloud_with(platforms=("edge",))


def test_random_changes_refuse_a_change_listed_twice():
    change = RequirementChange("A", add=(BIG,), remove=(SMALL,))
    with pytest.raises(ScenarioError, match="twice"):
        RandomChanges(changes=(change, change), mean_interval=60.0)


def test_a_run_without_a_world_plays_the_timelines_changes_and_initial_action_as_replay_does():
    """The World desmon run derives from a timeline keeps its requirement changes and
    joins (they were dropped: run started the detector and kept it, replay stopped it),
    and starts from the scenario's initial action (it started idle)."""
    r = RobotBuilder("r")
    r.platform("arm_pc", memory=512).device("ft", kind="force_sensor")
    r.platform("edge", memory=4096, on_demand=True, startup_s=5.0)
    with r.rpsl.perception_graph("force") as g:
        g.sensor("w", reads="force_sensor")
    r.depsl.deployment_specification("force").add_constraint("capacity", "memory", 300)
    r.rules({"hold": "force"})
    grow = RequirementChange("force", add=(Capacity("memory", 1000),), remove=(Capacity("memory", 300),))
    sc = Scenario(name="tl", model=r.build(),
                  timeline=(TimedEvent(0.0, ActionChange(HOLD), "t0"), TimedEvent(2.0, grow, "t1"), TimedEvent(4.0, PlatformJoin("edge"), "t2")))
    rep = replay(sc)
    replayed = [(str(c), ok) for s in rep.steps for c, ok in s.commands if ok is not None]
    run = simulate(sc, "desmon", seed=0)
    ran = [(f"{d['command']} {d['graph']} on {d['platform']}", d["ok"]) for d in run.decisions]
    assert ran == replayed == [("start force on arm_pc", True), ("stop force on arm_pc", True), ("start force on edge", True)], (ran, replayed)
    assert [(e.time, e.kind) for e in run.errors] == [(s.time, e.kind) for s in rep.steps for e in s.errors] == [(2.0, "no_acceptable_platforms")]
    assert run.metrics["risky_time_s"] == run.horizon  # holding from the start, as the initial action says


def test_scripted_joins_are_no_leased_time_as_estimate_and_sweep_plot_take_it():
    """cloud_offload without its lease, the edge server joining at 25 s and leaving at
    200 s by script: leased time counts the lease's joins only, so the run says 0 (it
    said 175 s), as desmon estimate knows without a run for a World that leases nothing."""
    import dataclasses
    from pathlib import Path

    from desmon.sim.metrics import run_figures

    path = Path(__file__).resolve().parents[1] / "scenarios" / "cloud_offload.py"
    base = load_scenario(str(path), {"lease": "False", "hours": "0.1"})
    joins = (TimedEvent(25.0, PlatformJoin("edge")), TimedEvent(200.0, PlatformLeave("edge")))
    scenario = dataclasses.replace(base, world=dataclasses.replace(base.world, changes=joins))
    result = simulate(scenario, seed=1)
    figures = run_figures(result.metrics, len(result.violations))
    assert figures["leases"] == 0 and figures["leased_s"] == 0.0
