"""The checker's state-backed QueryPort answers exactly as RepositoryQuery over networkx.

Every shipped scenario with checker bounds, both deployers: hypothesis draws event
sequences (with failing starts); after the initial reaction, after every step *and after
every Start/Stop inside a reaction* (both Control ports wrapped) the two answer every
query alike, including deployments() and the errors for unknown names.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as hst

from desmon.verify.state import StoreInsert
from desmon.errors import QueryError
from desmon.loader import load_scenario
from desmon.model.events import DeviceFail
from desmon.model.requirements import Selection
from desmon.verify import RepositoryRun
from desmon.verify.checker import Checker
from desmon.verify.strategies import choices

SCENARIOS = Path(__file__).resolve().parent.parent / "scenarios"
LOADED = {p.stem: load_scenario(p) for p in sorted(SCENARIOS.glob("*.py"))}
NAMES = [n for n, s in LOADED.items() if s.checker is not None]


def test_every_scenario_with_bounds_is_covered():
    assert {"memory_pressure", "vendor_selection", "symmetric_platforms", "coffee_handover"} <= set(NAMES)
    # vendor_selection exercises the Selection requirement through both query ports
    assert any(isinstance(r, Selection) for s in LOADED["vendor_selection"].model.specs for r in s.requirements)


def _error(f, *args):  # type: ignore[no-untyped-def]
    try:
        f(*args)
    except QueryError as e:
        return ("QueryError", str(e))
    return ("no error",)


def _answers(q, model):  # type: ignore[no-untyped-def]
    graphs = [g.name for g in model.graphs] + ["no_such_graph"]
    out = {"context": q.context(), "platform_states": q.platform_states(), "deployments": q.deployments()}
    for g in graphs:
        spec = q.deployment_information(g)
        out[("info", g)] = spec
        out[("deployed_on", g)] = q.deployed_on(g)
        if spec is not None:
            out[("fixed", g)] = q.fixed_platform(spec)
            out[("constraints", g)] = q.constraints(spec)
            out[("perception_graph", g)] = q.perception_graph(g)
    for p in model.platforms:
        out[("active", p.name)] = q.active_deployments(p.name)
        out[("platform_state", p.name)] = q.platform_state(p.name)
    out["unknown platform_state"] = _error(q.platform_state, "no_such_platform")
    out["unknown active"] = _error(q.active_deployments, "no_such_platform")
    out["unknown perception_graph"] = _error(q.perception_graph, "no_such_graph")
    return out


def _audit(control, query, model, seen):  # type: ignore[no-untyped-def]
    """Wrap ``control``'s start/stop (instance attributes): record the answers after each."""
    start, stop = control.start, control.stop

    def audited_start(graph, platform):  # type: ignore[no-untyped-def]
        ok = start(graph, platform)
        seen.append((f"start {graph} on {platform}", ok, _answers(query, model)))
        return ok

    def audited_stop(graph, platform):  # type: ignore[no-untyped-def]
        ok = stop(graph, platform)
        seen.append((f"stop {graph} on {platform}", ok, _answers(query, model)))
        return ok

    control.start, control.stop = audited_start, audited_stop


class Pair:
    """The checker's store and a networkx RepositoryRun, both Control ports audited."""

    def __init__(self, scenario, deployer):  # type: ignore[no-untyped-def]
        self.model = scenario.model
        self.checker = Checker(scenario, deployer)
        self.run = RepositoryRun(scenario, deployer, self.checker.bounds)
        self.key = self.checker.initial()
        assert self.key == self.run.key()
        self.compare()
        self.in_store: list = []
        self.in_repo: list = []
        _audit(self.checker.store, self.checker.store, self.model, self.in_store)
        _audit(self.run.control, self.run.query, self.model, self.in_repo)

    def compare(self) -> None:
        self.checker.store.load(self.key)
        assert _answers(self.checker.store, self.model) == _answers(self.run.query, self.model)

    def step(self, event, fails=()) -> int:  # type: ignore[no-untyped-def]
        """Both take ``event``; compare inside the reaction and after it; the commands compared."""
        self.in_store.clear()
        self.in_repo.clear()
        self.run.step(event, fails)
        prefix = tuple(i not in fails for i in range(max(fails) + 1)) if fails else ()
        self.key, _outcomes, _log, _instant = self.checker.run_one(self.key, event, prefix)
        # inside the reaction: the same commands, outcomes and answers after each
        assert [c for c, _ok, _a in self.in_store] == [c for c, _ok, _a in self.in_repo], f"commands of {event}"
        for (cmd, ok_s, a_s), (_cmd, ok_r, a_r) in zip(self.in_store, self.in_repo):
            assert ok_s == ok_r, f"{event}: {cmd}"
            assert a_s == a_r, f"{event}: answers after {cmd}"
        assert self.key == self.run.key(), f"after {event}"
        self.compare()
        return len(self.in_store)


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("deployer", ["desmon", "paper"])
@settings(max_examples=60, deadline=None, suppress_health_check=list(HealthCheck))
@given(data=hst.data())
def test_state_store_answers_like_repository(name, deployer, data):  # type: ignore[no-untyped-def]
    scenario = LOADED[name]
    seq = data.draw(choices(scenario, max_size=10))
    pair = Pair(scenario, deployer)
    for pick, fails in seq:
        enabled = pair.checker.enabled(pair.key)
        pair.step(enabled[pick % len(enabled)], fails)


def test_answers_are_compared_after_each_command_inside_a_reaction():
    # paper's Algorithm 2 migrates without a stop (start on pc2); desmon stops pc1 first
    for deployer, n in (("paper", 1), ("desmon", 2)):
        pair = Pair(LOADED["migration"], deployer)
        assert pair.step(DeviceFail("wrench_1")) == n
        assert pair.in_store[-1][0] == "start force_slip_detector on pc2"
    pair = Pair(LOADED["migration"], "desmon")
    assert pair.step(DeviceFail("wrench_1"), (0,)) == 2  # the start fails: compared too
    assert pair.in_store[-1][1] is False


def test_unknown_names_raise_like_repository():
    scenario = LOADED["coffee_handover"]
    checker = Checker(scenario)
    run = RepositoryRun(scenario)
    for q in (checker.store, run.query):
        with pytest.raises(QueryError, match="unknown platform 'nope'"):
            q.active_deployments("nope")
        with pytest.raises(QueryError, match="unknown platform 'nope'"):
            q.platform_state("nope")
        with pytest.raises(QueryError, match="unknown deployment 'nope'"):
            q.perception_graph("nope")


def test_a_load_back_at_zero_leaves_no_entry_in_either():
    """Canonical keys: load 100 then 0 is the initial (no-entry) state in both stores."""
    scenario = LOADED["migration"]
    checker = Checker(scenario)
    run = RepositoryRun(scenario, "desmon", checker.bounds)
    key = checker.initial()
    assert all(p != "pc1" for p, _items in key.loads)
    checker.store.load(key)
    for amount in (100, 0):
        assert StoreInsert(checker.store).set_load("pc1", "memory", amount)
        assert run.query.repo is run.repo
        from desmon.repository.facts import set_load

        assert set_load(run.repo, "pc1", "memory", amount)
    assert checker.store.key(frozenset(key.standing)) == key
    assert checker.store.platform_state("pc1").load == run.query.platform_state("pc1").load == ()
    assert not StoreInsert(checker.store).set_load("pc1", "memory", 0) and not set_load(run.repo, "pc1", "memory", 0)
