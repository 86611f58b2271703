"""One run context per run (desmon/deployment/run.py) and the memo wrapper of the Checks
port (desmon/deployment/memo.py): two runs in one process keep their own limits and
memos, however their calls interleave, and a memoised port answers as the port it wraps."""

from __future__ import annotations

from pathlib import Path

import pytest

from desmon.deployment.guard import Guard
from desmon.deployment.memo import MemoChecks
from desmon.deployment.run import RunContext
from desmon.deployment.validity import PlatformMemoChecks, ScalarChecks, check_validity, deployment_valid, spec_validity
from desmon.errors import ModelError
from desmon.loader import load_scenario
from desmon.sim.engine import SimWorld
from desmon.verify.checker import Checker, check, system_of

ROOT = Path(__file__).resolve().parent.parent
SCENARIOS = ROOT / "scenarios"


def _figures(result) -> tuple:
    return (result.verdict, result.states, result.transitions, result.incomplete, result.depth)


@pytest.fixture(scope="module")
def coffee():
    return load_scenario(SCENARIOS / "coffee_handover.py")


@pytest.fixture(scope="module")
def alone(coffee):
    """What each of the two runs gives on its own: two commands a reaction at most (the
    deployer crashes in a reaction that issues three) and a small search budget; and a
    whole search with the usual limits."""
    small = check(system_of(coffee, run=RunContext(guard=Guard(max_commands=2))), engine="direct", max_states=200)
    whole = check(system_of(coffee), engine="direct")
    assert small.verdict == "CRASHED" and whole.verdict != "CRASHED" and not whole.incomplete
    return _figures(small), _figures(whole)


def test_two_checks_with_different_limits_keep_their_own_when_they_alternate(coffee, alone):
    small = system_of(coffee, run=RunContext(guard=Guard(max_commands=2)))
    whole = system_of(coffee)
    assert small.run_context.checks is not whole.run_context.checks  # each run memoises on its own port
    assert small.store.checks is small.run_context.checks and small.core.guard is small.guard
    for _ in range(2):  # alternately, each search after the other's
        assert _figures(check(small, engine="direct", max_states=200)) == alone[0]
        assert _figures(check(whole, engine="direct")) == alone[1]
    assert small.guard.max_commands == 2 and whole.guard.max_commands != 2


def test_a_check_inside_a_simulation_leaves_the_simulation_as_it_runs_alone(coffee, alone):
    plain = SimWorld(coffee, seed=3, run=RunContext(guard=Guard(max_commands=500))).run()
    inner: list[tuple] = []

    def check_meanwhile(world: SimWorld) -> None:
        if len(inner) < 2:  # a check with other limits, in the middle of the run
            inner.append(_figures(check(system_of(coffee, run=RunContext(guard=Guard(max_commands=2))), engine="direct", max_states=200)))

    world = SimWorld(coffee, seed=3, run=RunContext(guard=Guard(max_commands=500)), on_quiescent=check_meanwhile)
    result = world.run()
    assert inner and all(figures == alone[0] for figures in inner)
    assert result.metrics == plain.metrics and result.violations == plain.violations
    assert world.core.guard.max_commands == 500
    assert type(world.run_context.checks.inner) is PlatformMemoChecks and not world.run_context.checks.answers


def test_a_context_and_another_guard_are_refused_and_a_guard_alone_makes_a_context(coffee):
    guard = Guard(max_commands=7)
    assert system_of(coffee, guard=guard).run_context.guard is guard
    run = RunContext(guard=guard)
    assert Checker(coffee, run=run, guard=guard).system.guard is guard  # the context's own guard: no conflict
    with pytest.raises(ModelError, match="pass the guard inside the context"):
        system_of(coffee, run=run, guard=Guard())


def test_a_context_with_checks_hands_them_to_the_run(coffee):
    checks = MemoChecks(ScalarChecks())
    system = system_of(coffee, run=RunContext(checks=checks))
    assert system.store.checks is checks
    check(system, engine="direct", max_states=30)
    assert checks.validity.cache_info().currsize > 0  # the run's answers went to the port it was given


def _questions(path: Path, limit: int):
    """(spec, states) pairs the checker meets on the first ``limit`` states of a scenario."""
    checker = Checker(load_scenario(path))
    checker.run(engine="direct", max_states=limit)
    store = checker.system.store
    for key in list(checker.explored)[:limit]:
        store.load(key)
        states = store.platform_states()
        for spec in store.current_specs():
            yield spec, states


@pytest.mark.parametrize("name", ["coffee_handover.py", "fallbacks.py", "memory_pressure.py", "vendor_selection.py", "platform_crash.py"])
def test_the_memo_wrapper_answers_as_the_checks_it_wraps(name):
    plain, parts = ScalarChecks(), PlatformMemoChecks()
    wrapped = [MemoChecks(ScalarChecks()), MemoChecks(PlatformMemoChecks(), answers=False)]
    asked = 0
    for spec, states in _questions(SCENARIOS / name, 60):
        reqs = spec.requirements
        for reasons in (True, False):
            want = spec_validity(reqs, spec.reads, states, states, spec.graph, reasons=reasons, checks=plain)
            for c in (*wrapped, parts):
                assert spec_validity(reqs, spec.reads, states, states, spec.graph, reasons=reasons, checks=c) == want
            assert check_validity(reqs, states, spec.graph, reasons=reasons, checks=wrapped[0]) == check_validity(reqs, states, spec.graph, reasons=reasons, checks=plain)
        for st in states:
            want = deployment_valid(spec, st, states, plain)
            assert all(deployment_valid(spec, st, states, c) == want for c in wrapped)
        asked += 1
    assert asked > 0
    assert wrapped[0].validity.cache_info().hits > 0  # the questions recur: the memo answered some


def test_the_memo_wrapper_keeps_one_joined_tuple_and_interns_per_instance():
    a, b = MemoChecks(ScalarChecks()), MemoChecks(ScalarChecks())
    made: list[int] = []

    def make(x: int) -> tuple[int]:
        made.append(x)
        return (x,)

    assert a.interned(("k", 1), make, 1) is a.interned(("k", 1), make, 1)
    assert b.interned(("k", 1), make, 1) == (1,) and made == [1, 1]  # b keeps its own
    a.clear()
    a.interned(("k", 1), make, 1)
    assert made == [1, 1, 1]
    assert MemoChecks(a).inner is a.inner  # wrapping a wrapper wraps what it wraps
    table = a.values("k")
    assert table is a.values("k") and table[("k", 1)] == (1,)  # interned reads and fills the table of its kind
    assert table.keep("x", 2) == 2 and table.get("x") == 2
    a.clear()
    assert not table and a.values("k") is table  # cleared in place: a kept table stays the memo's
