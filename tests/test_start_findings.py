"""Inside a reaction, the instantaneous invariants (single-instance, no-overcommit, fixed)
are charged to the start that breaks them, judged on what that start changed: the graph's
own instances, the capacities of the platform it started on that it adds to while they
are exceeded. A stop breaks none of them, and what the
environment had broken before the reaction (a requirement change that raised a running
graph's consumption) is no command's: the state the reaction ends in is judged whole.
Every engine audits with one function, :func:`desmon.deployment.invariants.start_findings`.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from desmon.cli import main
from desmon.deployment.invariants import SystemView, get_invariants, start_findings
from desmon.loader import load_scenario
from desmon.model.platform import Platform
from desmon.model.system import PlatformState
from desmon.verify.checker import Checker

ROOT = Path(__file__).resolve().parent.parent
RAISED = str(ROOT / "tests" / "data" / "raised_capacity.py")
INSTANT = get_invariants(["single-instance", "no-overcommit", "fixed"])


def _state(name: str, memory: float, *deployed: tuple[str, float]) -> PlatformState:
    return PlatformState(Platform.make(name, memory=memory), deployed=tuple((g, (("memory", m),)) for g, m in deployed))


def test_a_start_is_charged_with_what_it_breaks_on_its_platform_and_its_graph_not_what_stood_before():
    # pc over capacity before the start (the environment's doing); g started on pc2
    view = SystemView((_state("pc", 384, ("m", 400)), _state("pc2", 512, ("g", 100))), (), frozenset(), ())
    assert start_findings(view, INSTANT, "g", "pc2") == []
    # nor on pc itself with a graph that consumes nothing there: it adds nothing to it
    on_pc = SystemView((_state("pc", 384, ("m", 400), ("g", 0)),), (), frozenset(), ())
    assert start_findings(on_pc, INSTANT, "g", "pc") == []
    # a start that puts more on an exceeded capacity is charged: over it already, or taken over
    for before in (400, 300):
        more = SystemView((_state("pc", 384, ("m", before), ("g", 100)),), (), frozenset(), ())
        assert [n for n, _m in start_findings(more, INSTANT, "g", "pc")] == ["no-overcommit"]
    # a second instance of the started graph is charged; another graph's is not this start's
    twice = SystemView((_state("pc", 384, ("g", 100), ("h", 10)), _state("pc2", 512, ("g", 100), ("h", 10))), (), frozenset(), ())
    assert [n for n, _m in start_findings(twice, INSTANT, "g", "pc2")] == ["single-instance"]
    assert "g is active on 2 platforms" in start_findings(twice, INSTANT, "g", "pc2")[0][1]


@pytest.mark.parametrize("other", ["a_graph", "z_graph"])
def test_the_order_of_the_stops_the_environment_forced_decides_no_verdict(other, capsys):
    """Raising m_graph's Capacity over pc's capacity leaves both graphs to stop; whichever
    the deployer stops first (graph names decide it), no command broke no-overcommit."""
    scenario = load_scenario(RAISED, {"other": other})
    for engine in ("table", "direct"):
        res = Checker(scenario, "desmon").run(engine=engine)
        assert (res.verdict, res.states) == ("HOLDS", 2), (engine, res.reason)
    main(["run", RAISED, "-p", f"other={other}"])
    assert "INVARIANTS VIOLATED" not in capsys.readouterr().out
    assert main(["fuzz", RAISED, "-p", f"other={other}", "--examples", "30", "--no-progress"]) == 0


def test_a_start_of_an_instance_already_running_changes_nothing_and_is_charged_with_nothing(capsys):
    """Re-issuing Start for the running instances before repairing: no-ops, so the
    environment's over-commit is no more theirs in the world and the fuzzer than in the checker."""
    deployer = f"{RAISED}:restarts_first"
    assert main(["verify", RAISED, "--deployer", deployer, "--no-progress"]) == 0
    capsys.readouterr()
    main(["run", RAISED, "--deployer", deployer])
    assert "INVARIANTS VIOLATED" not in capsys.readouterr().out
    assert main(["fuzz", RAISED, "--deployer", deployer, "--examples", "30", "--no-progress"]) == 0


def test_a_generated_test_judges_the_starts_as_the_checker_does(tmp_path, capsys):
    """verify --pytest replays a violation inside a reaction with the same audit: it fails
    once the deployer is fixed, even though the environment had over-committed pc."""
    import re
    import subprocess
    import sys

    deployer = f"{RAISED}:tries_the_arm_first"
    py = tmp_path / "test_arm.py"
    assert main(["verify", RAISED, "--deployer", deployer, "--invariant", "no-overcommit", "--pytest", str(py), "--no-progress"]) == 1
    assert "right after `start a_graph on arm`" in capsys.readouterr().out
    run = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(py)]
    assert subprocess.run(run, capture_output=True, text=True, cwd=tmp_path).returncode == 0  # the bug: there
    py.write_text(re.sub(r"^DEPLOYER = .*$", "DEPLOYER = 'desmon'", py.read_text(), flags=re.M))  # the fix
    res = subprocess.run(run, capture_output=True, text=True, cwd=tmp_path)
    assert res.returncode == 1 and "no longer violates no-overcommit" in res.stdout, res.stdout
