"""The checker's state-backed QueryPort answers exactly as RepositoryQuery over networkx."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings

from desmon.loader import load_scenario
from desmon.verify.checker import Checker
from desmon.verify.machine import RepositoryRun
from desmon.verify.strategies import choices

SCENARIOS = Path(__file__).resolve().parent.parent / "scenarios"
NAMES = ["coffee_handover", "two_detectors", "shared_platform", "migration"]
LOADED = {n: load_scenario(SCENARIOS / f"{n}.py") for n in NAMES}


def _answers(q, model):  # type: ignore[no-untyped-def]
    graphs = [g.name for g in model.graphs] + ["no_such_graph"]
    out = {"context": q.context(), "platform_states": q.platform_states()}
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
    return out


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("deployer", ["desmon", "paper"])
@settings(max_examples=40, deadline=None, suppress_health_check=list(HealthCheck))
@given(data=__import__("hypothesis").strategies.data())
def test_state_store_answers_like_repository(name, deployer, data):  # type: ignore[no-untyped-def]
    scenario = LOADED[name]
    checker = Checker(scenario, deployer)
    seq = data.draw(choices(scenario, max_size=10))
    run = RepositoryRun(scenario, deployer, checker.bounds)
    key = checker.initial()
    assert key == run.key()
    checker.store.load(key)
    assert _answers(checker.store, scenario.model) == _answers(run.query, scenario.model)
    for pick, fails in seq:
        enabled = checker.enabled(key)
        event = enabled[pick % len(enabled)]
        run.step(event, fails)
        prefix = tuple(i not in fails for i in range(max(fails) + 1)) if fails else ()
        key, _outcomes, _log, _instant = checker.run_one(key, event, prefix)
        assert key == run.key(), f"after {event}"
        checker.store.load(key)
        assert _answers(checker.store, scenario.model) == _answers(run.query, scenario.model)


def test_unknown_names_raise_like_repository():
    from desmon.errors import QueryError

    scenario = LOADED["coffee_handover"]
    checker = Checker(scenario)
    run = RepositoryRun(scenario)
    for q in (checker.store, run.query):
        with pytest.raises(QueryError):
            q.active_deployments("nope")
        with pytest.raises(QueryError):
            q.perception_graph("nope")
