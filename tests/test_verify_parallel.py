"""``--workers``: forked worker processes expand BFS levels; the result never depends on N."""

from __future__ import annotations

import gc
import os
import re
from pathlib import Path

import pytest

import desmon.verify.direct as direct_module
import desmon.verify.parallel as parallel_module
from desmon.cli import main
from desmon.errors import CheckerError
from desmon.verify.system import TransitionSystem
from desmon.loader import load_scenario
from desmon.verify import Checker
from desmon.verify.mutants import MUTANTS

SCENARIOS = Path(__file__).resolve().parent.parent / "scenarios"


def pooled_levels(monkeypatch):  # type: ignore[no-untyped-def]
    """Send every level to the workers, and count the states they expanded."""
    monkeypatch.setattr(direct_module, "PARALLEL_LEVEL", 1)
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
        ("coffee_handover", "paper", {}),  # stops at the first violation, mid-level
        ("migration", "paper", {"keep_going": True}),  # four invariants
        ("migration", "make-before-break", {}),  # a violation inside a reaction, repaired before quiescence
        ("robot_day", "make-before-break", {"keep_going": True}),
        ("memory_pressure", "desmon", {}),  # HOLDS
        ("coffee_handover", "desmon", {"max_states": 300}),  # INCOMPLETE at the same state
    ],
)
@pytest.mark.parametrize("chunk", [1, 64])
def test_two_workers_give_the_same_result_as_one(monkeypatch, name, deployer, kw, chunk):
    scenario = load_scenario(SCENARIOS / f"{name}.py")
    variant = MUTANTS.get(deployer, deployer)
    c1 = Checker(scenario, variant)
    r1 = c1.run(**kw)
    one = _summary(r1, c1)
    seen = pooled_levels(monkeypatch)
    monkeypatch.setattr(parallel_module, "CHUNK", chunk)  # 1: keys cross chunk and worker boundaries
    c2 = Checker(scenario, variant)
    r2 = c2.run(workers=2, **kw)
    assert seen, "no level went to the workers"
    assert r2.workers == 2 and r2.worker_levels == len(seen)
    assert _summary(r2, c2) == one
    if deployer == "make-before-break" and not kw:
        assert r1.counterexamples[0].during, "the case meant to cover instantaneous violations has none"


@pytest.mark.slow
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


def test_cli_workers_flag_prints_the_same_report_but_for_timings(capsys, monkeypatch):
    path = str(SCENARIOS / "two_detectors.py")
    assert main(["verify", path, "--deployer", "paper", "--no-progress", "--engine", "direct"]) == 1
    one = capsys.readouterr().out
    seen = pooled_levels(monkeypatch)
    assert main(["verify", path, "--deployer", "paper", "--no-progress", "--workers", "2", "--engine", "direct"]) == 1
    two = capsys.readouterr().out
    assert seen
    timings = re.compile(r"  time: .*$", re.M)  # wall time, rates and peak memory differ
    assert timings.sub("", two) == timings.sub("", one)
    assert re.search(r"^states: [\d,]+  transitions: [\d,]+  depth: \d+", two, re.M)
    assert "workers, each at most" in two


def test_a_worker_that_dies_ends_the_search_with_a_one_line_error(monkeypatch, capsys):
    monkeypatch.setattr(direct_module, "PARALLEL_LEVEL", 1)
    real = TransitionSystem.expand
    parent = os.getpid()

    def dies_in_a_worker(self, key, known):  # type: ignore[no-untyped-def]
        if os.getpid() != parent and len(known) > 40:
            os._exit(9)  # as the out-of-memory killer would end it
        return real(self, key, known)

    monkeypatch.setattr(TransitionSystem, "expand", dies_in_a_worker)  # inherited by the forked workers
    assert main(["verify", str(SCENARIOS / "symmetric_platforms.py"), "--engine", "direct", "--workers", "2", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "worker process died" in err and "Traceback" not in err
    assert gc.isenabled()


def test_cli_rejects_zero_workers_with_exit_2(capsys):
    assert main(["verify", str(SCENARIOS / "coffee_handover.py"), "--workers", "0", "--no-progress"]) == 2
    assert "--workers must be positive" in capsys.readouterr().err
