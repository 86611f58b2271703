"""The first reaction's starts may fail, as every reaction's may: with ``start_failures=n``
the checker branches the initial reaction on up to ``n`` failing starts (each branch an
initial state), the fuzzer draws them, and every replay (``--replay``, ``--pytest``,
``explore``) takes them from the counterexample.

The scenario, tests/data/first_start_fails.py, scripts the world to fail the first start of
``g1`` on ``a`` at t=0; two deployers break an invariant only on that path.
"""

from __future__ import annotations

import json
from dataclasses import replace
import subprocess
import sys
from pathlib import Path

import pytest

from desmon.cli import main
from desmon.loader import load_scenario
from desmon.verify.checker import Checker
from desmon.verify.deployers import resolve_deployer
from desmon.verify.system import initial_states
from desmon.verify.trace import CHOSEN

ROOT = Path(__file__).resolve().parent.parent
SCENARIO = str(ROOT / "tests" / "data" / "first_start_fails.py")
SILENT = f"{SCENARIO}:silent"

#: deployer -> the invariant it breaks when the first reaction's start of g1 on a fails
BROKEN = {"desmon-keep-fallback": "preferred-when-possible", SILENT: "coverage"}
FIRST = f"initial [start g1 on a {CHOSEN}]"


def _world_violations(deployer: str, capsys) -> set[str]:  # type: ignore[no-untyped-def]
    main(["run", SCENARIO, "--deployer", deployer])
    out = capsys.readouterr().out
    below = out.split("INVARIANTS VIOLATED", 1)[1].splitlines()[1:] if "INVARIANTS VIOLATED" in out else []
    return {line.split()[1].rstrip(":") for line in below if line.strip().startswith("t=")}


@pytest.mark.parametrize("deployer", sorted(BROKEN))
def test_the_checker_finds_on_both_engines_what_the_world_breaks_when_a_first_start_fails(deployer, capsys):
    assert BROKEN[deployer] in _world_violations(deployer, capsys)
    scenario = load_scenario(SCENARIO)
    for engine in ("table", "direct"):
        res = Checker(scenario, resolve_deployer(deployer), invariants=[BROKEN[deployer]]).run(engine=engine)
        assert res.verdict == "VIOLATED", (engine, res.reason)
        c = res.counterexamples[0]
        assert c.initial_fails == (0,) and c.steps[0].title() == FIRST, (engine, c.steps[0])


def test_a_deployer_that_handles_a_failed_first_start_holds_with_one_initial_state_per_outcome(capsys):
    assert _world_violations("desmon", capsys) == set()
    scenario = load_scenario(SCENARIO)
    counts = {e: Checker(scenario, "desmon").run(engine=e) for e in ("table", "direct")}
    assert {r.verdict for r in counts.values()} == {"HOLDS"}
    assert counts["table"].states == counts["direct"].states
    # the first reaction starts g1 on a; failing it is a second initial state (g2 on a)
    none_fail = initial_states(Checker(scenario, "desmon", bounds=replace(scenario.checker, start_failures=0)).system)
    both = initial_states(Checker(scenario, "desmon").system)
    assert [f for f, _k, _b in none_fail] == [()] and [f for f, _k, _b in both] == [(), (0,)]
    assert both[0][1].deployments == (("g1", "a"),) and both[1][1].deployments == (("g2", "a"),)


def test_a_counterexample_through_a_failed_first_start_replays_from_its_json_and_its_generated_test(tmp_path, capsys):
    js, py = tmp_path / "cex.json", tmp_path / "test_cex.py"
    assert main(["verify", SCENARIO, "--deployer", SILENT, "--json", str(js), "--pytest", str(py), "--no-progress"]) == 1
    out = capsys.readouterr().out
    assert f"0. {FIRST}" in out
    first = json.loads(js.read_text())["counterexamples"][0]["states"][0]
    assert first["fail_indices"] == [0] and first["failed_starts"] == ["start g1 on a"]
    assert main(["verify", SCENARIO, "--deployer", SILENT, "--replay", str(js)]) == 1
    replayed = capsys.readouterr().out
    assert f"0. {FIRST}" in replayed and "coverage                 VIOLATED" in replayed
    res = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(py)], capture_output=True, text=True, cwd=tmp_path)
    assert res.returncode == 0 and "1 passed" in res.stdout, res.stdout + res.stderr
    assert "initial_fails=(0,)" in py.read_text()
    # edited: without the first reaction's failure the replay leaves the recorded states
    data = json.loads(js.read_text())
    data["counterexamples"][0]["states"][0].update(fail_indices=[], failed_starts=[])
    js.write_text(json.dumps(data))
    assert main(["verify", SCENARIO, "--deployer", SILENT, "--replay", str(js)]) == 1
    assert "step 0 diverges" in capsys.readouterr().out
    # edited: a failing start the first reaction never issues is refused in one line
    data["counterexamples"][0]["states"][0].update(fail_indices=[3], failed_starts=["start g1 on a"])
    js.write_text(json.dumps(data))
    assert main(["verify", SCENARIO, "--deployer", SILENT, "--replay", str(js)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "fail start #4 of the reaction, which issues 1 real start now" in err, err


def test_fuzz_draws_the_failure_of_a_first_start(capsys):
    assert main(["fuzz", SCENARIO, "--deployer", SILENT, "--examples", "50"]) == 1
    out = capsys.readouterr().out
    assert "VIOLATED coverage after 0 steps" in out and f"0. {FIRST}" in out


def test_what_a_failing_choice_breaks_inside_the_first_reaction_counts_where_it_ends_as_another_did():
    """``doubles`` ends its first reaction with g2 on b whether its start there fails or
    not; only the failing choice runs g2 twice on the way, and both engines report it."""
    scenario = load_scenario(SCENARIO)
    for engine in ("table", "direct"):
        res = Checker(scenario, resolve_deployer(f"{SCENARIO}:doubles"), invariants=["single-instance"]).run(engine=engine)
        assert res.verdict == "VIOLATED", engine
        c = res.counterexamples[0]
        assert (c.length, c.initial_fails, c.during) == (0, (0,), "start g2 on b"), engine
    assert len(initial_states(Checker(scenario, resolve_deployer(f"{SCENARIO}:doubles")).system)) == 1  # one initial state


def test_a_deployer_that_fails_only_when_a_first_start_fails_crashed_in_a_reachable_state(tmp_path, capsys):
    """It runs with every start succeeding, so it is no bad input (exit 2) but CRASHED (exit
    4) with the path to it, in verify, fuzz, explore and the world alike."""
    crashes = f"{SCENARIO}:crashes"
    assert main(["verify", SCENARIO, "--deployer", crashes, "--no-progress"]) == 4
    out = capsys.readouterr().out
    assert "CRASHED in the reaction of step 0" in out and f"0. {FIRST}" in out and "the deployer failed in step 0" in out
    assert main(["fuzz", SCENARIO, "--deployer", crashes, "--examples", "30", "--no-progress"]) == 4
    assert f"0. {FIRST}" in capsys.readouterr().out
    assert main(["explore", SCENARIO, "--deployer", crashes, "--verify", "--no-progress", "-o", str(tmp_path / "c.html")]) == 4
    assert "with start #1 failing): raised RuntimeError: a start failed" in capsys.readouterr().err
    assert main(["run", SCENARIO, "--deployer", crashes]) == 4  # (the world's script fails that start at t=0)
    assert "desmon: CRASHED: at t=0 s" in capsys.readouterr().err


def test_the_explorer_shows_what_the_first_reaction_did(tmp_path, capsys):
    page = tmp_path / "p.html"
    assert main(["explore", SCENARIO, "--deployer", SILENT, "--verify", "--no-progress", "-o", str(page)]) == 0
    text = page.read_text(encoding="utf-8")
    assert "start g1 on a: FAILED" in text


def test_a_deployer_that_fails_on_a_refused_first_start_cannot_run_at_all_in_every_command(capsys):
    """A refused start is no choice and no failure of the world's: failing on it in the
    first reaction is bad input (exit 2) for verify, run and replay alike."""
    path = str(ROOT / "tests" / "data" / "refused_first_start.py")
    for command in ("verify", "run", "replay"):
        assert main([command, path, "--deployer", f"{path}:raises"]) == 2, command
        err = capsys.readouterr().err
        assert err.startswith("desmon: error: ") and "RuntimeError: a start did not work" in err, (command, err)
