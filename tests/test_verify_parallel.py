"""``--workers``: forked worker processes expand BFS levels; the result never depends on N."""

from __future__ import annotations

from pathlib import Path

import pytest

import desmon.verify.checker as checker_module
import desmon.verify.parallel as parallel_module
from desmon.cli import main
from desmon.errors import CheckerError
from desmon.loader import load_scenario
from desmon.verify import Checker

SCENARIOS = Path(__file__).resolve().parent.parent / "scenarios"


def pooled_levels(monkeypatch):  # type: ignore[no-untyped-def]
    """Send every level to the workers, and count the states they expanded."""
    monkeypatch.setattr(checker_module, "PARALLEL_LEVEL", 1)
    seen = []
    real = parallel_module.ExpansionPool.expand

    def spy(self, frontier):  # type: ignore[no-untyped-def]
        seen.append(len(frontier))
        return real(self, frontier)

    monkeypatch.setattr(parallel_module.ExpansionPool, "expand", spy)
    return seen


def _summary(r, c):  # type: ignore[no-untyped-def]
    return (
        r.verdict, r.reason, r.states, r.transitions, r.depth,
        dict(r.enabled), dict(r.new_states), dict(r.changed), dict(r.rules), dict(r.branches),
        [(x.invariant, x.events, x.during, x.message) for x in r.counterexamples],
        list(c.explored),
    )


@pytest.mark.parametrize(
    "name, deployer, kw",
    [
        ("coffee_handover", "paper", {"keep_going": True}),  # several invariants, instantaneous ones too
        ("coffee_handover", "paper", {}),  # stops at the first violation, mid-level
        ("migration", "paper", {"keep_going": True}),
        ("memory_pressure", "desmon", {}),  # HOLDS
        ("coffee_handover", "desmon", {"max_states": 300}),  # INCOMPLETE at the same state
    ],
)
def test_two_workers_give_the_same_result_as_one(monkeypatch, name, deployer, kw):
    scenario = load_scenario(SCENARIOS / f"{name}.py")
    c1 = Checker(scenario, deployer)
    one = _summary(c1.run(**kw), c1)
    seen = pooled_levels(monkeypatch)
    c2 = Checker(scenario, deployer)
    r2 = c2.run(workers=2, **kw)
    assert seen, "no level went to the workers"
    assert r2.workers == 2
    assert _summary(r2, c2) == one


def test_two_workers_with_symmetry_reduction_give_the_same_result(monkeypatch):
    scenario = load_scenario(SCENARIOS / "symmetric_platforms.py")
    c1 = Checker(scenario, "desmon", symmetry=True)
    one = _summary(c1.run(keep_going=True), c1)
    seen = pooled_levels(monkeypatch)
    c2 = Checker(scenario, "desmon", symmetry=True)
    assert _summary(c2.run(keep_going=True, workers=2), c2) == one
    assert seen


def test_fewer_than_one_worker_is_refused():
    with pytest.raises(CheckerError, match="--workers"):
        Checker(load_scenario(SCENARIOS / "coffee_handover.py")).run(workers=0)


def test_cli_workers_flag_prints_the_same_verdict_and_state_count(capsys, monkeypatch):
    path = str(SCENARIOS / "two_detectors.py")
    assert main(["verify", path, "--deployer", "paper", "--no-progress"]) == 1
    one = capsys.readouterr().out
    seen = pooled_levels(monkeypatch)
    assert main(["verify", path, "--deployer", "paper", "--no-progress", "--workers", "2"]) == 1
    assert seen
    two = capsys.readouterr().out
    pick = lambda text: [line for line in text.splitlines() if not line.startswith("states:")]  # noqa: E731
    assert pick(two) == pick(one)
    assert "workers, each at most" in two


def test_cli_rejects_zero_workers_with_exit_2(capsys):
    assert main(["verify", str(SCENARIOS / "coffee_handover.py"), "--workers", "0", "--no-progress"]) == 2
    assert "--workers must be positive" in capsys.readouterr().err
