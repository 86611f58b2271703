"""The fast paths of the transition give the answers of the plain definitions.

* ``validity_for`` with the store's identity memo (``StateStore.validity_memo``) and
  without it (the plain ``check_validity`` path the repository takes);
* ``DeploymentCore.settle`` (only the deployments of previous ∪ raised graphs are
  tested, no view) and the definition ``standing_after(previous, raised, slots,
  validly_active(view), active)``;
* the corrected reaction (``ensure_deployed`` split into ``_survey`` / ``_act_on`` so a
  kept graph costs no generator, validity answers memoised) and the reaction as it was
  written before those fast paths (kept here as the reference).

Every state the checker reaches in a few scenarios, every enabled event, every start
outcome prefix of length <= 1.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from desmon.deployment.core import standing_after
from desmon.deployment.deployer import Deployer, _active_graphs, _noting_starts, _second_chance, _stop_graphs
from desmon.deployment.ports import (
    DEPLOYMENT_FAILED, DEPLOYMENT_INFORMATION_MISSING, NO_ACCEPTABLE_PLATFORMS, STOPPING_FAILED, RaiseError, Start, Stop,
)
from desmon.deployment.invariants import validly_active
from desmon.deployment.validity import spec_validity, validity_for
from desmon.loader import load_scenario
from desmon.verify import Checker

SCENARIOS = Path(__file__).resolve().parent.parent / "scenarios"
NAMES = ["coffee_handover", "memory_pressure", "fixed_platform", "vendor_selection", "platform_crash", "robot_day"]


def _reference_ensure_deployed(g, q):  # type: ignore[no-untyped-def]
    """ensure_deployed as it was before the _survey / _act_on split (break-before-make)."""
    spec = q.deployment_information(g)
    if spec is None:
        yield RaiseError(DEPLOYMENT_INFORMATION_MISSING, g)
        return False
    fixed = q.fixed_platform(spec)
    world = q.platform_states()
    candidates = [s for s in world if fixed is None or s.name == fixed]
    acceptable = spec_validity(q.constraints(spec), spec.reads, candidates, world, g).acceptable
    current = q.deployed_on(g)
    keep = next((p for p in current if p in acceptable), None)
    for p in [p for p in current if p != keep]:
        if not (yield Stop(g, p)):
            yield RaiseError(STOPPING_FAILED, g, p)
            return False
    if keep is not None:
        return True
    if not acceptable:
        explained = spec_validity(q.constraints(spec), spec.reads, candidates, world, g).explain()
        yield RaiseError(NO_ACCEPTABLE_PLATFORMS, g, fixed, explained if fixed is None else f"fixed platform {fixed}: {explained}")
        return False
    for pk in acceptable:
        if (yield Start(g, pk)):
            return True
        yield RaiseError(DEPLOYMENT_FAILED, g, pk)
    return False


def _reference_react(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    placed: dict[str, bool] = {}
    tried: dict[str, set[str]] = {}
    yield from _noting_starts(_reference_body(q, slots, changed, context_changed, placed), tried)
    yield from _second_chance(q, slots, placed, tried)


def _reference_body(q, slots, changed, context_changed, placed):  # type: ignore[no-untyped-def]
    """The corrected reaction as it was before the fast paths: every graph placed by the
    unsplit ensure_deployed (above), no memo of the validity answers."""

    def place(g):  # type: ignore[no-untyped-def]
        if g not in placed:
            placed[g] = yield from _reference_ensure_deployed(g, q)
        return placed[g]

    for p in changed:
        for d in q.active_deployments(p):
            yield from place(q.perception_graph(d))
    for g, _p in q.deployments():  # the readers of a changed platform's devices
        spec = q.deployment_information(g)
        if spec is not None and any(h in changed for r in spec.reads for h in r.hosts):
            yield from place(g)
    wanted = {g for slot in slots for g in slot}
    yield from _stop_graphs([g for g in _active_graphs(q) if g not in wanted], q)
    chosen: set[str] = set()
    for slot in slots:
        for g in slot:
            if (yield from place(g)):
                chosen.add(g)
                break
    yield from _stop_graphs([g for g in _active_graphs(q) if g in wanted and g not in chosen], q)


REFERENCE = Deployer("reference", "desmon on ensure_deployed, unsplit", _reference_react)


def _plain_validity(q, spec, reasons):  # type: ignore[no-untyped-def]
    states = q.platform_states()
    fixed = q.fixed_platform(spec)
    if fixed is not None:
        states = tuple(s for s in states if s.name == fixed)
    return spec_validity(q.constraints(spec), spec.reads, states, q.platform_states(), spec.graph, reasons=reasons)


@pytest.mark.parametrize("name", NAMES)
def test_fast_paths_match_the_definitions(name):
    scenario = load_scenario(SCENARIOS / f"{name}.py")
    fast = Checker(scenario, "desmon")
    fast.run(max_states=3000)
    ref = Checker(scenario, REFERENCE)
    st, core = fast.store, fast.core
    checked = 0
    for key in fast.explored:
        for event in fast.enabled(key):
            for prefix in ((), (False,)):
                nkey, outcomes, log, _instant = fast.run_one(key, event, prefix)
                # the reaction: same commands, same outcomes, same next state
                rkey, routcomes, rlog, _ = ref.run_one(key, event, prefix)
                assert (nkey, outcomes, log.commands) == (rkey, routcomes, rlog.commands)
                # settle: the definition on a view of the state reached
                st.load(nkey)
                raised = [e.graph for e in log.errors]
                view = core.view()
                active = frozenset(g for g, _p in view.deployments)
                expect = standing_after(frozenset(key.standing), raised, view.slots, validly_active(view), active)
                assert frozenset(nkey.standing) == expect
                # validity_for: memoised (twice, to hit the memo) and plain
                for spec in scenario.model.specs:
                    for reasons in (False, True):
                        plain = _plain_validity(st, spec, reasons)
                        assert validity_for(st, spec, reasons=reasons) == plain
                        assert validity_for(st, spec, reasons=reasons) == plain
                checked += 1
    assert checked > 10
