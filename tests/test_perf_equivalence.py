"""The fast paths of the transition give the answers of the plain definitions.

* ``validity_for`` with the store's identity memo (``StateStore.validity_memo``) and
  without it (the plain ``check_validity`` path the repository takes);
* ``DeploymentCore.settle`` (only the deployments of previous ∪ raised graphs are
  tested, no view) and the definition ``standing_after(previous, raised, wanted,
  validly_active(view))``;
* the corrected reaction (``ensure_deployed`` split into ``_survey`` / ``_act_on`` so a
  kept graph costs no generator) and a reaction built on ``ensure_deployed`` itself.

Every state the checker reaches in a few scenarios, every enabled event, every start
outcome prefix of length <= 1.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from desmon.deployment.core import StepLog, run_sync, standing_after
from desmon.deployment.deployer import Deployer, _stop_graphs, _active_graphs, ensure_deployed
from desmon.deployment.invariants import validly_active
from desmon.deployment.validity import check_validity, validity_for
from desmon.loader import load_scenario
from desmon.verify import Checker

SCENARIOS = Path(__file__).resolve().parent.parent / "scenarios"
NAMES = ["coffee_handover", "memory_pressure", "fixed_platform", "vendor_selection", "platform_crash", "robot_day"]


def _reference_react(q, slots, changed, context_changed):  # type: ignore[no-untyped-def]
    """The corrected reaction written on ensure_deployed as a whole (the pre-split form)."""
    placed: dict[str, bool] = {}

    def place(g):  # type: ignore[no-untyped-def]
        if g not in placed:
            placed[g] = yield from ensure_deployed(g, q)
        return placed[g]

    for p in changed:
        for d in q.active_deployments(p):
            yield from place(q.perception_graph(d))
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
    return check_validity(q.constraints(spec), states, spec.graph, reasons=reasons)


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
                wanted = frozenset(g for slot in view.slots for g in slot)
                expect = standing_after(frozenset(key.standing), raised, wanted, validly_active(view))
                assert frozenset(nkey.standing) == expect
                # validity_for: memoised (twice, to hit the memo) and plain
                for spec in scenario.model.specs:
                    for reasons in (False, True):
                        plain = _plain_validity(st, spec, reasons)
                        assert validity_for(st, spec, reasons=reasons) == plain
                        assert validity_for(st, spec, reasons=reasons) == plain
                checked += 1
    assert checked > 10
