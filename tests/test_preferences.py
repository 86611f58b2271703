"""Soft preferences: they never reject a platform, they order the acceptable
ones by score; rebalancing moves a valid deployment only on a gain above its threshold."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from hypothesis import given, settings, strategies as st

from desmon.cli import main
from desmon.deployment import DeploymentCore
from desmon.deployment.validity import check_validity, platform_score
from desmon.errors import ModelError
from desmon.model import Device, Platform, PlatformState, RobotBuilder, make_requirement as req
from desmon.model.events import ActionChange, LoadChange
from desmon.model.requirements import Preference, make_preference as pref
from desmon.repository import ImmediateControl, Repository, RepositoryInsert, RepositoryQuery, load_model


def state(name, memory=512, *, up=True, devices=(), load=0.0, deployed=(), attributes=None, preference=0.0):
    p = Platform.make(name, memory=memory, attributes=attributes, preference=preference)
    return PlatformState(
        p,
        up=up,
        devices=tuple(Device(f"{name}-{i}-{k}", k, name, vendor=v) for i, (k, v) in enumerate(devices)),
        load=(("memory", load),),
        deployed=tuple((g, (("memory", a),)) for g, a in deployed),
    )


# ---------------------------------------------------------------- scoring and order


def test_a_higher_score_comes_first_whatever_the_declaration_order():
    a, b = state("a", attributes={"os": "qnx"}), state("b", attributes={"os": "linux"})
    v = check_validity([pref("attribute", "os", "linux")], [a, b])
    assert v.acceptable == ("b", "a")
    assert v.scores == (1.0, 0.0)


def test_equal_scores_keep_declaration_order():
    states = [state(n, attributes={"os": "linux"}) for n in ("c", "a", "b")]
    v = check_validity([pref("attribute", "os", "linux")], states)
    assert v.acceptable == ("c", "a", "b")


def test_scores_the_users_numbers_make_equal_tie_whatever_the_float_rounding():
    """0.3 against 0.1 + 0.2 (0.30000000000000004 in binary) had put the later platform first."""
    a = state("a", attributes={"fast": "yes"})
    b = state("b", attributes={"quiet": "yes", "cool": "yes"})
    prefs = [pref("attribute", "fast", "yes", weight=0.3), pref("attribute", "quiet", "yes", weight=0.1), pref("attribute", "cool", "yes", weight=0.2)]
    v = check_validity(prefs, [a, b])
    assert v.acceptable == ("a", "b") and v.scores[0] == v.scores[1] and v.gain("b") == 0.0
    # a gain of 0.4 - 0.3 is 0.1 (not 0.10000000000000003): not above a min_gain of 0.1
    c = state("c", attributes={"fast": "yes", "quiet": "yes"})
    v = check_validity([pref("attribute", "fast", "yes", weight=0.3), pref("attribute", "quiet", "yes", weight=0.1)], [a, c])
    assert v.acceptable == ("c", "a") and v.gain("a") == 0.1 and not v.gain("a") > 0.1


def test_equal_scores_keep_the_platform_preference_before_declaration_order():
    low, high = state("low", preference=0.0), state("high", preference=5.0)
    assert check_validity([pref("spread")], [low, high]).acceptable == ("high", "low")


def test_a_preference_never_rejects_a_platform_that_scores_zero():
    bare = state("bare")  # no attribute, no device, full load: every term is 0
    full = state("full", load=512)
    prefs = [pref("vendor", "tactile_pad", "weiss"), pref("attribute", "os", "linux"), pref("least_loaded", "memory")]
    v = check_validity(prefs, [bare, full])
    assert set(v.acceptable) == {"bare", "full"}
    assert v.rejected == ()


def test_hard_requirements_still_reject_when_preferences_are_present():
    small, big = state("small", memory=100), state("big", memory=1024)
    v = check_validity([req("capacity", "memory", 200), pref("least_loaded", "memory")], [small, big])
    assert v.acceptable == ("big",)
    assert [f.platform for f in v.failures("small")] == ["small"]


def test_a_weight_scales_its_term():
    s = state("a", load=128)  # least_loaded term 1 - 128/512 = 0.75
    one = check_validity([pref("least_loaded", "memory")], [s]).score("a")
    three = check_validity([pref("least_loaded", "memory", weight=3)], [s]).score("a")
    assert one == pytest.approx(0.75)
    assert three == pytest.approx(3 * one)


def test_a_heavier_preference_outweighs_a_lighter_one():
    linux = state("linux", attributes={"os": "linux", "site": "far"})
    near = state("near", attributes={"os": "qnx", "site": "near"})
    prefs = [pref("attribute", "os", "linux", weight=1), pref("attribute", "site", "near", weight=2)]
    assert check_validity(prefs, [linux, near]).acceptable == ("near", "linux")


def test_vendor_scores_only_a_working_device_of_that_vendor():
    weiss = state("w", devices=[("tactile_pad", "weiss")])
    other = state("o", devices=[("tactile_pad", "acme")])
    v = check_validity([pref("vendor", "tactile_pad", "weiss")], [other, weiss])
    assert v.acceptable == ("w", "o")
    assert (v.score("w"), v.score("o")) == (1.0, 0.0)


def test_most_free_counts_the_graphs_own_share_as_free():
    # 'g' itself holds 256 MB here: for placing g, the platform is entirely free
    s = state("a", memory=512, deployed=[("g", 256)])
    assert check_validity([pref("most_free", "memory")], [s], graph="g").score("a") == pytest.approx(1.0)
    assert check_validity([pref("most_free", "memory")], [s], graph="h").score("a") == pytest.approx(0.5)


def test_most_free_subtracts_background_load_and_others():
    s = state("a", memory=1000, load=100, deployed=[("other", 400)])
    assert check_validity([pref("most_free", "memory")], [s], graph="g").score("a") == pytest.approx(0.5)


def test_least_loaded_reads_background_load_only():
    s = state("a", memory=1000, load=250, deployed=[("other", 500)])
    assert check_validity([pref("least_loaded", "memory")], [s], graph="g").score("a") == pytest.approx(0.75)


def test_colocate_scores_a_platform_where_a_named_graph_is_deployed():
    with_force = state("a", deployed=[("force", 50)])
    empty = state("b")
    v = check_validity([pref("colocate", "force", "tactile")], [empty, with_force], graph="combined")
    assert v.acceptable == ("a", "b")
    assert (v.score("a"), v.score("b")) == (1.0, 0.0)


def test_colocate_does_not_count_the_graph_itself():
    s = state("a", deployed=[("combined", 250)])
    assert check_validity([pref("colocate", "force")], [s], graph="combined").score("a") == 0.0


def test_spread_prefers_the_platform_with_fewer_other_graphs():
    busy = state("busy", deployed=[("x", 10), ("y", 10)])
    quiet = state("quiet", deployed=[("z", 10)])
    mine = state("mine", deployed=[("g", 10)])  # only the graph itself: counts as empty
    v = check_validity([pref("spread")], [busy, quiet, mine], graph="g")
    assert v.acceptable == ("mine", "quiet", "busy")
    assert [v.score(p) for p in v.acceptable] == pytest.approx([1.0, 0.5, 1 / 3])


def test_without_preferences_scores_are_empty_and_gain_is_zero():
    v = check_validity([req("capacity", "memory", 10)], [state("a"), state("b")])
    assert v.scores == () and v.breakdown == ()
    assert v.gain("b") == 0.0


def test_gain_is_how_much_the_best_platform_beats_the_given_one():
    v = check_validity([pref("least_loaded", "memory")], [state("a", load=256), state("b", load=0)])
    assert v.gain("a") == pytest.approx(0.5)
    assert v.gain("b") == 0.0


# ---------------------------------------------------------------- explain


def test_explain_shows_a_breakdown_per_platform_that_sums_to_its_score():
    prefs = [pref("attribute", "os", "linux", weight=2), pref("least_loaded", "memory", weight=0.5)]
    states = [state("a", attributes={"os": "linux"}, load=128), state("b", attributes={"os": "qnx"})]
    v = check_validity(prefs, states)
    lines = v.explain().splitlines()
    assert lines[0] == "acceptable: a, b"
    score_lines = [line for line in lines if line.startswith("score ")]
    assert [line.split(":")[0] for line in score_lines] == ["score a", "score b"]
    for name, terms in v.breakdown:
        assert sum(value for _what, value in terms) == pytest.approx(v.score(name))
        assert [what for what, _v in terms] == [p.describe() for p in prefs]


def _scenario_file(tmp_path: Path) -> Path:
    path = tmp_path / "prefs.py"
    path.write_text(
        "from desmon.model import RobotBuilder\n"
        "from desmon.model.events import ActionChange, LoadChange\n"
        "from desmon.model.scenario import Scenario, TimedEvent\n"
        "robot = RobotBuilder('r')\n"
        "robot.platform('pc1', memory=512).device('ft', kind='force_sensor')\n"
        "robot.platform('pc2', memory=512)\n"
        "with robot.rpsl.perception_graph('A') as g:\n"
        "    g.sensor('s', reads='force_sensor')\n"
        "robot.depsl.deployment_specification('A').add_constraint('capacity', 'memory', 100)"
        ".prefer('least_loaded', 'memory', weight=2)\n"
        "robot.rules({'grasp': ['A']})\n"
        "scenario = Scenario(name='prefs', model=robot.build(), initial=(LoadChange('pc1', 256),),\n"
        "    timeline=(TimedEvent(1.0, ActionChange('grasp'), 't1'),))\n",
        encoding="utf-8",
    )
    return path


def test_desmon_explain_prints_a_score_line_for_each_acceptable_platform(tmp_path, capsys):
    assert main(["explain", str(_scenario_file(tmp_path)), "A", "--at", "t1"]) == 0
    out = capsys.readouterr().out
    assert "acceptable: pc2, pc1" in out
    assert "score pc2: 2 = prefer least_loaded(memory) x2 2" in out
    assert "score pc1: 1 = prefer least_loaded(memory) x2 1" in out


# ---------------------------------------------------------------- the DSL


def test_prefer_adds_a_soft_preference_beside_the_hard_requirements():
    robot = RobotBuilder()
    spec = robot.depsl.deployment_specification("g").add_constraint("capacity", "memory", 10).prefer("spread", weight=2).build()
    assert spec.hard == (req("capacity", "memory", 10),)
    assert spec.preferences == (Preference("spread", (), 2.0),)


def test_rebalance_is_refused_without_a_preference():
    robot = RobotBuilder()
    with pytest.raises(ModelError, match="no preference to score platforms by"):
        robot.depsl.deployment_specification("g").add_constraint("capacity", "memory", 10).rebalance(0.5).build()


@pytest.mark.parametrize(
    "call, fragment",
    [
        (lambda s: s.prefer("vendr", "tactile_pad", "weiss"), "did you mean 'vendor'"),
        (lambda s: s.prefer("most_free"), "got 0 argument(s)"),
        (lambda s: s.prefer("spread", weight=math.nan), "weight = nan is not a number"),
        (lambda s: s.prefer("spread", weight=0), "weight = 0 is not positive"),
        (lambda s: s.prefer("spread", weight="2"), "is a string, not a number"),
        (lambda s: s.prefer("spread", wieght=2), "did you mean 'weight'"),
        (lambda s: s.prefer("spread").rebalance(-1), "min_gain of 'g' = -1 is negative"),
        (lambda s: s.prefer("spread").rebalance(math.inf), "is not finite"),
        (lambda s: s.prefer("spread", weight=1e308), "weight 1e+308: over 1000, a score keeps none of the 12 decimals"),
        (lambda s: s.prefer("spread", weight=1000.5), "scale every weight of the specification down alike"),
    ],
    ids=["kind-typo", "no-resource", "weight-nan", "weight-zero", "weight-text", "keyword-typo", "rebalance-negative", "rebalance-inf",
         "weight-overflows", "weight-past-the-decimals"],
)
def test_a_bad_preference_is_refused_with_one_line_naming_it(call, fragment):
    with pytest.raises(ModelError) as info:
        call(RobotBuilder().depsl.deployment_specification("g")).build()
    assert fragment in str(info.value)
    assert "\n" not in str(info.value)


def _fleet_with(preference: tuple) -> RobotBuilder:
    robot = RobotBuilder("r")
    robot.platform("pc", memory=512, attributes={"onboard": "yes"}).device("ft", kind="force_sensor", vendor="ati")
    for name in ("A", "B"):
        with robot.rpsl.perception_graph(name) as g:
            g.sensor("s", reads="force_sensor")
    robot.depsl.deployment_specification("A").add_constraint("capacity", "memory", 10).prefer(*preference)
    return robot


@pytest.mark.parametrize(
    "preference, fragment",
    [
        (("most_free", "memroy"), "no platform declares a 'memroy' capacity (did you mean 'memory'?)"),
        (("attribute", "onbord", "yes"), "no platform declares an attribute 'onbord'"),
        (("attribute", "onboard", "yse"), "no platform has onboard = 'yse'"),
        (("vendor", "force_sensr", "ati"), "no device is of kind 'force_sensr'"),
        (("vendor", "force_sensor", "kuka"), "no force_sensor device is made by 'kuka'"),
        (("colocate", "C"), "there is no perception graph 'C'"),
        (("colocate", "A"), "it names its own graph 'A'"),
    ],
    ids=["resource", "attribute", "attribute-value", "device-kind", "vendor", "graph", "itself"],
)
def test_a_preference_naming_what_the_model_lacks_is_refused_when_the_model_is_built(preference, fragment):
    with pytest.raises(ModelError, match="would prefer") as info:
        _fleet_with(preference).build()
    assert fragment in str(info.value)


# ---------------------------------------------------------------- the deployer: rebalancing


def _deployed(min_gain: float | None):
    robot = RobotBuilder("r")
    robot.platform("pc1", memory=512).device("ft", kind="force_sensor")
    robot.platform("pc2", memory=512)
    with robot.rpsl.perception_graph("A") as g:
        g.sensor("s", reads="force_sensor")
    spec = robot.depsl.deployment_specification("A").add_constraint("capacity", "memory", 100).prefer("least_loaded", "memory")
    if min_gain is not None:
        spec.rebalance(min_gain)
    robot.rules({"grasp": ["A"]})
    model = robot.build()
    repo = Repository()
    load_model(repo, model)
    control = ImmediateControl(repo)
    core = DeploymentCore(model, RepositoryQuery(repo), RepositoryInsert(repo, "r"), "desmon")
    core.step(ActionChange("grasp"), control)
    assert RepositoryQuery(repo).deployments() == (("A", "pc1"),)  # a tie: declaration order
    return core, repo, control


def test_a_valid_deployment_stays_when_the_gain_equals_min_gain():
    core, repo, control = _deployed(0.25)
    _stim, log = core.step(LoadChange("pc1", 128), control)  # gain 128/512 = 0.25: not above
    assert [str(c) for c, _ok in log.decisions] == []
    assert RepositoryQuery(repo).deployments() == (("A", "pc1"),)


def test_a_valid_deployment_moves_stop_before_start_when_the_gain_exceeds_min_gain():
    core, repo, control = _deployed(0.25)
    _stim, log = core.step(LoadChange("pc1", 256), control)  # gain 0.5 > 0.25
    assert [str(c) for c, _ok in log.decisions] == ["stop A on pc1", "start A on pc2"]
    assert RepositoryQuery(repo).deployments() == (("A", "pc2"),)


def test_without_rebalance_a_valid_deployment_never_moves_for_a_better_score():
    core, repo, control = _deployed(None)
    _stim, log = core.step(LoadChange("pc1", 400), control)  # gain 0.78, still valid
    assert [str(c) for c, _ok in log.decisions] == []
    assert RepositoryQuery(repo).deployments() == (("A", "pc1"),)


def test_rebalance_zero_moves_on_any_positive_gain_but_not_on_a_tie():
    core, repo, control = _deployed(0.0)
    core.step(LoadChange("pc1", 0), control)
    assert RepositoryQuery(repo).deployments() == (("A", "pc1"),)
    core.step(LoadChange("pc1", 8), control)
    assert RepositoryQuery(repo).deployments() == (("A", "pc2"),)


# ---------------------------------------------------------------- property


_KINDS = ("force_sensor", "tactile_pad")
_VENDORS = ("weiss", "kuka")


@st.composite
def fleets(draw):
    n = draw(st.integers(1, 6))
    states = []
    for i in range(n):
        memory = draw(st.sampled_from([128, 256, 512, 1024]))
        devices = draw(st.lists(st.tuples(st.sampled_from(_KINDS), st.sampled_from(_VENDORS)), max_size=2))
        deployed = draw(st.lists(st.tuples(st.sampled_from(["g", "x", "y"]), st.sampled_from([0, 50, 100])), max_size=2, unique_by=lambda d: d[0]))
        states.append(
            state(
                f"p{i}",
                memory=memory,
                up=draw(st.booleans()) or i == 0,
                devices=devices,
                load=draw(st.sampled_from([0, 32, 64, 200])),
                deployed=deployed,
                attributes={"os": draw(st.sampled_from(["linux", "qnx"]))},
                preference=draw(st.sampled_from([0.0, 0.0, 1.0])),
            )
        )
    return states


preferences = st.one_of(
    st.tuples(st.just("vendor"), st.sampled_from(_KINDS), st.sampled_from(_VENDORS)),
    st.tuples(st.just("attribute"), st.just("os"), st.sampled_from(["linux", "qnx"])),
    st.tuples(st.just("most_free"), st.just("memory")),
    st.tuples(st.just("least_loaded"), st.just("memory")),
    st.tuples(st.just("colocate"), st.sampled_from(["x", "y"])),
    st.tuples(st.just("spread")),
)


@settings(max_examples=150, deadline=None)
@given(
    states=fleets(),
    prefs=st.lists(st.tuples(preferences, st.sampled_from([0.5, 1.0, 2.0])), max_size=3),
    need=st.sampled_from([0, 100, 300]),
)
def test_preferences_only_permute_the_acceptable_platforms_best_first(states, prefs, need):
    hard = [req("capacity", "memory", need)] if need else []
    soft = [pref(*p, weight=w) for p, w in prefs]
    plain = check_validity(hard, states, graph="g")
    scored = check_validity(hard + soft, states, graph="g")
    assert sorted(scored.acceptable) == sorted(plain.acceptable)
    assert scored.rejected == plain.rejected
    by_name = {s.name: s for s in states}
    if soft:
        values = [platform_score(soft, by_name[p], "g") for p in scored.acceptable]
        assert list(scored.scores) == pytest.approx(values)
        assert all(a >= b for a, b in zip(values, values[1:]))
        # ties keep the order the platforms have without preferences
        for a, b in zip(scored.acceptable, scored.acceptable[1:]):
            if scored.score(a) == scored.score(b):
                assert plain.acceptable.index(a) < plain.acceptable.index(b)
    else:
        assert scored.acceptable == plain.acceptable


def test_the_same_preference_twice_and_two_rebalance_thresholds_are_refused():
    from desmon.model.dsl import SpecBuilder

    with pytest.raises(ModelError, match="prefers spread\\(\\) twice"):
        SpecBuilder("g").prefer("spread").prefer("spread", weight=2)
    with pytest.raises(ModelError, match="rebalances twice"):
        SpecBuilder("g").prefer("spread").rebalance(0.5).rebalance(0.7)
