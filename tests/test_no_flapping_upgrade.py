"""``no-flapping`` judges only the moves the rebalancing rule makes: a fallback stopped for
an upgrade whose start fails, and placed again on another platform, did not flap."""

from __future__ import annotations

import dataclasses

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as hst

from desmon.deployment import DeploymentCore
from desmon.model import HOLD, RobotBuilder
from desmon.model.events import ActionChange, LoadChange
from desmon.model.scenario import Scenario, TimedEvent
from desmon.repository import ImmediateControl, Repository, RepositoryInsert, RepositoryQuery, load_model
from desmon.sim.engine import simulate
from desmon.sim.world import Step, StartFailure, World
from desmon.verify import Bounds, Checker
from desmon.verify.mutants import MUTANTS
from test_verify_table_preferences import preference_scenarios
from test_verify_table import _both  # everything a user sees of a result, engine against engine


def _upgrade_model():  # type: ignore[no-untyped-def]
    """Slot (combined, tactile): combined needs pc0's force sensor and 850 MB, so it fits
    on pc0 only when pc0's load is 100 MB and tactile (100 MB) is not there. tactile
    prefers the most free memory and rebalances above a gain of 0.5."""
    r = RobotBuilder("upgrade_flap")
    r.platform("pc0", memory=1000).device("wrench", kind="force_sensor")
    r.platform("pc1", memory=1000)
    for g in ("combined", "tactile"):
        with r.rpsl.perception_graph(g) as gb:
            gb.sensor("s", reads="force_sensor")
            gb.processing("p", inputs=["s"])
    r.depsl.deployment_specification("combined").add_constraint("attribute", "platform_has", "force_sensor").add_constraint(
        "capacity", "memory", 850
    )
    r.depsl.deployment_specification("tactile").add_constraint("capacity", "memory", 100).prefer("most_free", "memory").rebalance(0.5)
    r.rules({HOLD: [("combined", "tactile")]})
    return r.build()


#: pc0 250 MB and pc1 300 MB: combined has no room, tactile runs on pc0 (0.75 free beats
#: 0.70). pc1 drops to 0: pc1 beats pc0 by 0.25, not above 0.5, tactile stays. pc0 drops
#: to 100: combined would fit on pc0 without tactile, so the upgrade stops tactile.
INITIAL = (LoadChange("pc0", 250), LoadChange("pc1", 300))
EVENTS = (LoadChange("pc1", 0), LoadChange("pc0", 100))


def _upgrade_scenario(start_failures: int) -> Scenario:
    return Scenario(
        name="upgrade_flap", model=_upgrade_model(), initial=INITIAL, timeline=(TimedEvent(0, ActionChange(HOLD)),),
        checker=Bounds(actions=(HOLD,), loads={"pc0": (100, 250), "pc1": (0, 300)}, start_failures=start_failures),
    )


def test_a_fallback_stopped_for_an_upgrade_whose_start_fails_and_placed_again_elsewhere_is_no_unjustified_move():
    model = _upgrade_model()
    repo = Repository()
    load_model(repo, model)
    query = RepositoryQuery(repo)
    control = ImmediateControl(repo, fails=lambda g, p: g == "combined")
    core = DeploymentCore(model, query, RepositoryInsert(repo, model.robot), "desmon")
    for event in (*INITIAL, ActionChange(HOLD), EVENTS[0]):
        core.step(event, control)
    assert query.deployments() == (("tactile", "pc0"),)  # a gain of 0.25 moved nothing
    _stim, log = core.step(EVENTS[1], control)
    assert [(str(c), ok) for c, ok in log.decisions] == [
        ("stop tactile on pc0", True), ("start combined on pc0", False), ("start tactile on pc1", True),
    ]
    assert core.unjustified == []


def test_a_failed_upgrade_that_places_a_rebalancing_fallback_again_elsewhere_is_not_reported_as_flapping_on_both_engines():
    d, t, r = _both(_upgrade_scenario(start_failures=1), "desmon", keep_going=True)
    assert t == d
    assert r.verdict == "HOLDS", [c.message for c in r.counterexamples]


def test_the_simulation_audit_reports_no_flapping_for_a_failed_upgrade():
    world = World(
        task=(Step(HOLD, 30.0),), horizon=30.0, signals=False,
        loads=(TimedEvent(10.0, EVENTS[0]), TimedEvent(20.0, EVENTS[1])),
        start_failure=StartFailure(script=(("combined", "pc0", 1),)),
    )
    scenario = dataclasses.replace(_upgrade_scenario(0), world=world)
    result = simulate(scenario, seed=0)
    assert result.metrics["start_failures"] == 1  # the upgrade was attempted and failed
    assert RepositoryQuery(result.repo).deployments() == (("tactile", "pc1"),)  # placed again, best-first
    assert [v for v in result.violations if v[1] == "no-flapping"] == []


def test_the_no_hysteresis_mutant_is_still_caught_moving_the_fallback_on_the_upgrade_model_on_both_engines():
    for kw in ({}, {"keep_going": True}):
        d, t, r = _both(_upgrade_scenario(start_failures=1), MUTANTS["no-hysteresis"], **kw)
        assert t == d
        assert r.verdict == "VIOLATED" and r.counterexamples[0].invariant == "no-flapping"
        assert "tactile moved from pc0" in r.counterexamples[0].message and "not above its min_gain 0.5" in r.counterexamples[0].message


@pytest.mark.slow
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(preference_scenarios(), hst.sampled_from(["desmon", "desmon-keep-fallback"]), hst.integers(1, 2))
def test_the_corrected_deployers_never_flap_on_generated_models_with_fallbacks_and_failing_starts(scenario, deployer, failures):
    scenario = dataclasses.replace(scenario, checker=dataclasses.replace(scenario.checker, start_failures=failures))
    r = Checker(scenario, deployer).run(engine="auto", max_states=3000)
    assert not [c.message for c in r.counterexamples if c.invariant == "no-flapping"]


def test_two_rebalancing_graphs_that_swap_platforms_without_gain_are_two_unjustified_moves():
    """A deployer that stops both graphs of two slots, then starts each where the other ran:
    the start of one between the other's stop and restart does not hide either move."""
    from desmon.deployment.deployer import Deployer
    from desmon.deployment.ports import Start, Stop

    r = RobotBuilder("swap")
    r.platform("pc0", memory=1000)
    r.platform("pc1", memory=1000)
    for g in ("a", "b"):
        with r.rpsl.perception_graph(g) as gb:
            gb.sensor("s", reads="force_sensor")
            gb.processing("p", inputs=["s"])
        r.depsl.deployment_specification(g).add_constraint("capacity", "memory", 100).prefer("most_free", "memory").rebalance(0.5)
    r.rules({HOLD: [("a",), ("b",)]})
    model = r.build()

    def react(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
        on = dict(q.deployments())
        if not on:
            yield Start("a", "pc0")
            yield Start("b", "pc1")
            return
        yield Stop("a", on["a"])
        yield Stop("b", on["b"])
        yield Start("a", on["b"])
        yield Start("b", on["a"])

    repo = Repository()
    load_model(repo, model)
    q = RepositoryQuery(repo)
    core = DeploymentCore(model, q, RepositoryInsert(repo, model.robot), Deployer("swap", "stops both, then starts both", react))
    control = ImmediateControl(repo, fails=lambda g, p: False)
    core.step(ActionChange(HOLD), control)
    core.step(LoadChange("pc0", 10), control)
    assert dict(q.deployments()) == {"a": "pc1", "b": "pc0"}
    assert [line.split()[0] for line in core.unjustified] == ["a", "b"]
