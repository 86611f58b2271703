"""The checker: pinned verdicts, the paper's bugs, traces, CLI behaviour."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

from desmon.cli import main
from desmon.errors import CheckerError, NondeterminismError
from desmon.loader import load_scenario
from desmon.model.events import ActionChange, DeviceFail, PlatformDown
from desmon.verify import HOLDS, INCOMPLETE, VIOLATED, Bounds, Checker
from desmon.verify.report import format_result

ROOT = Path(__file__).resolve().parent.parent
SCENARIOS = ROOT / "scenarios"
NAMES = [
    "coffee_handover", "two_detectors", "shared_platform", "migration",
    "platform_crash", "memory_pressure", "vendor_selection", "robot_day", "fixed_platform", "fallbacks",
]


@pytest.mark.parametrize(
    "name, deployer",
    [(n, d) for n in NAMES for d in ("desmon", "paper")] + [("fallbacks", "desmon-keep-fallback")],
)
def test_pinned_verdicts_and_state_counts(name, deployer):
    scenario = load_scenario(SCENARIOS / f"{name}.py")
    want = scenario.expected["verify"][deployer]
    r = Checker(scenario, deployer).run(keep_going=True)
    assert r.verdict == want["verdict"]
    assert r.states == want["states"]
    assert {c.invariant: c.length for c in r.counterexamples} == want["counterexamples"]


@pytest.mark.parametrize("name", NAMES + ["../docs/examples/kitchen_robot"])
def test_continue_lists_every_invariant_checking_it_alone_breaks_with_the_same_shortest_length(name):
    """``--continue`` is ``--invariant NAME`` for every invariant at once: it lists each
    invariant that checking it alone finds broken, with a counterexample as short. It goes
    on past the states that break an invariant (on ``migration`` the paper's overcommit
    takes 2 steps through a single-instance violation, 4 around it), and a transition
    carries every invariant its reaction breaks inside it, not only the first (the
    paper's ``preferred-when-possible`` on the coffee handover breaks in the reactions
    that break ``errors-justified``; on the scenario guide's kitchen robot the first
    reaction that breaks it alone does so after 3 steps, one that breaks another
    invariant first after 2). Both engines."""
    scenario = load_scenario(SCENARIOS / f"{name}.py")
    for engine in ("table", "direct"):
        r = Checker(scenario, "paper").run(keep_going=True, engine=engine)
        listed = {c.invariant: c.length for c in r.counterexamples}
        alone = {}
        for inv in r.invariants:
            one = Checker(scenario, "paper", invariants=[inv]).run(engine=engine)
            if one.counterexamples:
                alone[inv] = one.counterexamples[0].length
        assert listed == alone, (engine, listed, alone)
        assert r.verdict == VIOLATED and r.reason == ", ".join(listed)


def test_continue_cut_by_a_budget_says_its_list_is_partial():
    """A ``--continue`` search that a budget ends early keeps its reason: what it found is
    not all there is, and the verdict says so."""
    r = Checker(load_scenario(SCENARIOS / "coffee_handover.py"), "paper").run(keep_going=True, max_states=300)
    assert r.verdict == VIOLATED and r.incomplete
    assert r.reason.endswith("(search incomplete: max states 300 reached)"), r.reason


def test_desmon_holds_on_coffee_from_cli(capsys):
    assert main(["verify", str(SCENARIOS / "coffee_handover.py"), "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "verdict: HOLDS" in out and "states: 693" in out
    assert "events (enabled / new states)" in out and "deployer branches" in out


def _cex(name, invariant, deployer="paper"):
    r = Checker(load_scenario(SCENARIOS / f"{name}.py"), deployer, invariants=[invariant]).run()
    assert r.verdict == VIOLATED
    return r.counterexamples[0]


def test_algorithm1_returns_after_first_graph_coverage():
    c = _cex("two_detectors", "coverage")
    assert [str(s.event) for s in c.steps[1:]] == ["action grasp"]
    assert "tactile_slip_detector" in c.message


def test_algorithm2_migrates_without_stopping_single_instance():
    c = _cex("migration", "single-instance")
    assert [s.event for s in c.steps[1:]] == [DeviceFail("wrench_1")]
    assert c.steps[-1].key.deployments == (("force_slip_detector", "pc1"), ("force_slip_detector", "pc2"))


def test_algorithm1_fixed_start_without_check_no_overcommit():
    c = _cex("migration", "no-overcommit")
    # wrench_1 fails, the force detector is duplicated onto pc2, then the fixed tactile
    # detector is started on pc2 without a capacity check.
    assert c.length == 2
    assert [s.event for s in c.steps[1:]] == [DeviceFail("wrench_1"), ActionChange("move_base")]


def test_algorithm2_returns_after_first_deployment_valid_or_error():
    c = _cex("shared_platform", "valid-or-error")
    assert [s.event for s in c.steps[1:]] == [ActionChange("move_base"), PlatformDown("main_pc")]
    assert "vision_slip_detector" in c.message


def test_trace_format_numbered_steps():
    c = _cex("two_detectors", "coverage")
    text = format_result(Checker(load_scenario(SCENARIOS / "two_detectors.py"), "paper").run())
    assert " 0. initial -> context hold" in text
    assert " 1. action grasp -> IN_CONTEXT hold => grasp; +force_slip_detector -[DEPLOYED_ON]-> arm_pc" in text
    assert c.length == 1


@pytest.mark.slow
def test_cli_paper_json_and_generated_pytest(tmp_path, capsys):
    js, py = tmp_path / "cex.json", tmp_path / "test_cex.py"
    rc = main(["verify", str(SCENARIOS / "migration.py"), "--deployer", "paper", "--continue", "--json", str(js), "--pytest", str(py), "--no-progress"])
    assert rc == 1
    data = json.loads(js.read_text())
    assert data["verdict"] == "VIOLATED"
    lengths = {c["invariant"]: c["length"] for c in data["counterexamples"]}
    assert lengths["single-instance"] == 1
    assert data["counterexamples"][0]["states"][0]["state"]["context"] == "hold"
    res = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(py)], capture_output=True, text=True, cwd=tmp_path)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "6 passed" in res.stdout
    src = py.read_text()  # a replay through the networkx repository, not a copy of the bootstrap
    assert "from desmon.verify import RepositoryRun" in src and "ScriptedControl" not in src and "run_sync" not in src


def test_the_json_holds_what_the_text_says_the_search_exercised(tmp_path, capsys):
    """The events enabled and the new states per kind, the dead kinds, the selector contexts
    and the deployer's branches: the text report's lines, written to the JSON too."""
    js = tmp_path / "r.json"
    main(["verify", str(SCENARIOS / "migration.py"), "--deployer", "paper", "--continue", "--json", str(js), "--no-progress"])
    text, data = capsys.readouterr().out, json.loads(js.read_text())
    events = ", ".join(f"{k} {v['enabled']:,}/{v['new_states']:,}" for k, v in data["events"].items())
    assert f"events (enabled / new states): {events}\n" in text
    assert "selector contexts exercised: " + ", ".join(f"{c} {n:,}" for c, n in data["contexts"]) in text
    assert "deployer branches: " + ", ".join(f"{b} {n:,}" for b, n in data["branches"].items()) in text
    assert data["dead_event_kinds"] == []  # (a VIOLATED search warns of none)


@pytest.mark.slow
def test_generated_pytest_replays_an_instantaneous_violation(tmp_path):
    """The make-before-break mutant breaks single-instance only inside the reaction: the
    generated test replays it through RepositoryRun with an audit after every command."""
    from desmon.verify.mutants import get_mutant
    from desmon.verify.report import counterexample_pytest

    path = SCENARIOS / "migration.py"
    scenario = load_scenario(path)
    checker = Checker(scenario, get_mutant("make-before-break"), invariants=["single-instance"])
    r = checker.run()
    assert r.counterexamples[0].during == "start force_slip_detector on pc2"
    src = counterexample_pytest(r, str(path), checker.bounds.start_action(scenario))
    assert "from desmon.verify import RepositoryRun" in src and "class ScriptedControl" not in src
    py = tmp_path / "test_cex_during.py"
    py.write_text(src)
    res = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(py)], capture_output=True, text=True, cwd=tmp_path)
    assert res.returncode == 0 and "1 passed" in res.stdout, res.stdout + res.stderr


def test_incomplete_and_limits(capsys):
    path = str(SCENARIOS / "coffee_handover.py")
    assert main(["verify", path, "--max-states", "50", "--no-progress"]) == 3
    assert "INCOMPLETE (max states 50 reached)" in capsys.readouterr().out
    assert main(["verify", path, "--max-depth", "2", "--no-progress"]) == 3
    assert "max depth 2" in capsys.readouterr().out


def test_invariant_selection_and_bad_input(capsys, tmp_path):
    path = str(SCENARIOS / "migration.py")
    assert main(["verify", path, "--deployer", "paper", "--invariant", "fixed", "--no-progress"]) == 0
    assert main(["verify", path, "--invariant", "nope", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("desmon: error: unknown invariant 'nope'") and err.count("\n") == 1
    assert main(["verify", str(tmp_path / "missing.py")]) == 2
    bad = tmp_path / "bad.py"
    bad.write_text("from desmon.model.scenario import Scenario\nfrom desmon.model import RobotBuilder\nr = RobotBuilder(); r.platform('p')\nscenario = Scenario(name='x', model=r.build())\n")
    assert main(["verify", str(bad)]) == 2
    assert "declares no checker bounds" in capsys.readouterr().err


def test_history_is_left_to_the_audit_and_the_fuzzer(capsys):
    """The checker's states have no running list / stops / history edges: it cannot fail there."""
    path = str(SCENARIOS / "two_detectors.py")
    assert main(["verify", path, "--no-progress"]) == 0
    head = capsys.readouterr().out.splitlines()[0]
    checked = head.split("invariants: ")[1].split(" (")[0].split(", ")
    assert "history" not in checked and checked == [
        "valid-or-error", "no-overcommit", "single-instance", "coverage", "errors-current", "fixed",
        "errors-justified", "preferred-when-possible", "no-flapping",
    ]
    assert head.endswith("(not history: sim audit and fuzz only)")
    assert main(["verify", path, "--invariant", "history", "--no-progress"]) == 2
    cap = capsys.readouterr()
    assert cap.out == "" and cap.err.count("\n") == 1
    assert cap.err.startswith("desmon: error: --invariant history: the checker cannot evaluate it")
    assert "desmon fuzz" in cap.err
    with pytest.raises(CheckerError, match="cannot evaluate"):
        Checker(load_scenario(path), invariants=["coverage", "history"])
    r = Checker(load_scenario(path), invariants=["coverage"]).run()
    assert r.invariants == ("coverage",) and r.not_checked == ()


def test_bad_bounds_are_rejected():
    scenario = load_scenario(SCENARIOS / "coffee_handover.py")
    with pytest.raises(CheckerError, match="unknown device"):
        Checker(scenario, bounds=Bounds(devices=("nope",)))
    with pytest.raises(CheckerError, match="not one of its levels"):
        Checker(scenario, bounds=Bounds(loads={"torso_pc": (0, 100)}))
    with pytest.raises(CheckerError, match=r"load levels of 'torso_pc' repeat a level \(\[600, 700, 700, 800\]\)"):
        Checker(scenario, bounds=Bounds(loads={"torso_pc": (600, 700, 700, 800)}))


def test_nondeterminism_is_reported():
    scenario = load_scenario(SCENARIOS / "two_detectors.py")
    c = Checker(scenario)
    init = c.initial()
    k1, *_ = c.run_one(init, ActionChange("grasp"), ())
    with pytest.raises(NondeterminismError):
        c.replay([(ActionChange("grasp"), ())], expect=[init, init])
    assert k1 != init


def test_progress_goes_to_stderr(capsys):
    # a zero threshold makes the short coffee run report progress (every 256 expansions)
    r = Checker(load_scenario(SCENARIOS / "coffee_handover.py")).run(progress=True, progress_after=0.0, progress_every=0.0)
    assert r.verdict == HOLDS
    cap = capsys.readouterr()
    assert cap.out == ""
    lines = [ln for ln in cap.err.split("\r") if "states/s" in ln]
    assert lines, cap.err
    assert "states" in lines[-1] and "transitions" in lines[-1] and "depth" in lines[-1]
    assert cap.err.endswith("\n")  # the progress line is closed before the report


def test_timeout_gives_incomplete():
    # coffee needs > 256 expansions (the timeout is checked every 256): a 1 ns budget is spent by then
    r = Checker(load_scenario(SCENARIOS / "coffee_handover.py")).run(timeout=1e-9)
    assert r.verdict == INCOMPLETE
    assert "timeout" in r.reason and r.states < 747


def _normal(key):  # type: ignore[no-untyped-def]
    """The state a key denotes, independent of how it is spelled (zero loads dropped, parts as sets)."""
    loads = frozenset((p, r, a) for p, items in key.loads for r, a in items if a != 0)
    return (key.context, frozenset(key.failed), frozenset(key.down), loads, frozenset(key.deployments), frozenset(key.standing))


@pytest.mark.parametrize("name", NAMES + ["symmetric_platforms"])
@pytest.mark.parametrize("deployer", ["desmon", "paper"])
def test_explored_keys_are_canonical(name, deployer):
    """No two explored keys denote the same state (e.g. a load back at 0 is no entry, as initially)."""
    scenario = load_scenario(SCENARIOS / f"{name}.py")
    c = Checker(scenario, deployer)
    c.run(keep_going=True)
    assert len({_normal(k) for k in c.explored}) == len(c.explored)
    for k in c.explored:
        assert all(items and all(a != 0 for _r, a in items) for _p, items in k.loads)
        assert list(k.failed) == sorted(k.failed) and list(k.down) == sorted(k.down)
        assert list(k.deployments) == sorted(k.deployments) and list(k.standing) == sorted(k.standing)


@pytest.mark.parametrize("name", ["two_detectors", "shared_platform", "migration"])
def test_scenarios_run_as_scripts(name):
    res = subprocess.run([sys.executable, str(SCENARIOS / f"{name}.py")], capture_output=True, text=True)
    assert res.returncode == 0 and "verdict: HOLDS" in res.stdout
    res = subprocess.run([sys.executable, str(SCENARIOS / f"{name}.py"), "paper"], capture_output=True, text=True)
    assert res.returncode == 1 and "VIOLATED" in res.stdout


_GARBAGE_PROBE = """
import gc, sys
from desmon.loader import load_scenario
from desmon.verify import Checker
scenario = load_scenario(sys.argv[1])
checker = Checker(scenario, sys.argv[2])
checker.initial()  # the checker's own (long-lived) cycles exist before the search
Checker(scenario, sys.argv[2]).run(max_states=2)  # so do the modules a search imports (numpy's lazy ones too)
gc.collect()
gc.set_debug(gc.DEBUG_SAVEALL)  # whatever a collection finds is kept in gc.garbage
r = checker.run(keep_going=True)
assert gc.isenabled(), "run() must give the collector back"
gc.collect()
print(r.states, len(gc.garbage))
"""


@pytest.mark.parametrize("deployer", ["desmon", "paper"])
def test_search_leaves_no_cyclic_garbage_so_pausing_the_collector_is_safe(deployer):
    """Run in a fresh interpreter: threads other tests leave behind (a Dask client's
    event loop) make garbage of their own while the collector is paused."""
    out = subprocess.run(
        [sys.executable, "-c", _GARBAGE_PROBE, str(SCENARIOS / "migration.py"), deployer], capture_output=True, text=True, check=True
    ).stdout.split()
    states, garbage = int(out[0]), int(out[1])
    assert states == load_scenario(SCENARIOS / "migration.py").expected["verify"][deployer]["states"]
    assert garbage == 0


def test_a_transition_property_is_reported_as_broken_by_the_reaction_as_a_whole(capsys):
    """preferred-when-possible judges a whole reaction, not one of its commands: the report
    says so instead of naming a command it came "right after"."""
    from desmon.verify.trace import WHOLE_REACTION, where_in_reaction

    assert main(["verify", str(SCENARIOS / "two_detectors.py"), "--deployer", "paper", "--no-progress"]) == 1
    out = capsys.readouterr().out
    assert "VIOLATED preferred-when-possible after 1 step (shortest), by the reaction as a whole:" in out
    assert "right after `the reaction`" not in out
    assert where_in_reaction(WHOLE_REACTION) == "by the reaction as a whole"
    assert where_in_reaction("start x on p") == "during the reaction, right after `start x on p`"
    assert where_in_reaction(None) == ""


def test_a_generated_pytest_replays_a_violation_of_the_initial_state(tmp_path, capsys):
    """A counterexample of 0 steps (the initial reaction already violates): the generated
    test checks the initial state and passes while the bug is there."""
    py = tmp_path / "test_initial.py"
    rc = main(["verify", str(SCENARIOS / "symmetric_platforms.py"), "--deployer", "paper", "--pytest", str(py), "--no-progress"])
    out = capsys.readouterr().out
    assert rc == 1 and "after 0 steps" in out, out
    found = out.count(" after 0 steps (shortest)")  # the state's coverage, and what the initial reaction as a whole broke
    assert found == 2 and "preferred-when-possible after 0 steps (shortest), by the reaction as a whole" in out, out
    res = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(py)], capture_output=True, text=True, cwd=tmp_path)
    assert res.returncode == 0 and f"{found} passed" in res.stdout, res.stdout + res.stderr


def test_a_generated_pytest_runs_for_a_scenario_whose_script_defines_a_requirement_kind(tmp_path, capsys):
    """A kind defined in the scenario script has no module a fresh process can import: the
    generated test looks it up once the scenario is loaded. Another scenario's --pytest
    made afterwards in this process does not ask for it either (it once imported every
    kind ever registered, from modules that were gone)."""
    edges = Path(__file__).parent / "data" / "interchangeable_edge_boxes.py"
    for name, args in (("test_own_kind.py", [str(edges), "-p", "avoid=true", "--deployer", "mutant:no-recheck"]),
                       ("test_after.py", [str(SCENARIOS / "symmetric_platforms.py"), "--deployer", "paper"])):
        assert main(["verify", *args, "--pytest", str(tmp_path / name), "--no-progress"]) == 1
        out = capsys.readouterr().out
        res = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", name], capture_output=True, text=True, cwd=tmp_path)
        assert res.returncode == 0 and " passed" in res.stdout, out + res.stdout + res.stderr


def test_a_generated_pytest_compiles_and_names_its_scenario_whatever_characters_its_path_holds(tmp_path):
    """The path is only in SCENARIO (a Python literal): a folder named with three double
    quotes once ended the module's docstring, and the file did not compile."""
    import ast
    import shutil

    folder = tmp_path / 'q"""d\\n'
    folder.mkdir()
    path = folder / "migration.py"
    shutil.copy(SCENARIOS / "migration.py", path)
    py = tmp_path / "test_odd.py"
    assert main(["verify", str(path), "--deployer", "paper", "--pytest", str(py), "--no-progress"]) == 1
    tree = ast.parse(py.read_text())  # a SyntaxError here: the path broke out of a string
    (scenario,) = [ast.literal_eval(n.value) for n in tree.body if isinstance(n, ast.Assign) and n.targets[0].id == "SCENARIO"]
    assert scenario == str(path)


EARLY = '''
from desmon.deployment.deployer import DESMON
from desmon.deployment.ports import NO_ACCEPTABLE_PLATFORMS, RaiseError


def react(q, slots, changed, context_changed):
    """desmon's, except that on entering move_base it gives up on everything (a bug of step 1 only)"""
    if context_changed and q.context() == "move_base":
        for slot in slots:
            for g in slot:
                yield RaiseError(NO_ACCEPTABLE_PLATFORMS, g)
        return
    yield from DESMON.react(q, slots, changed, context_changed)
'''


def test_a_generated_test_of_a_transition_property_judges_the_step_the_checker_named(tmp_path, capsys):
    """The paper's errors-justified counterexample on migration without start failures is
    3 steps long, entering move_base at step 1: its test must fail for a deployer that
    breaks the property at step 1 only (the audit had gathered findings of every step and
    passed)."""
    py, scenario = tmp_path / "test_mig.py", tmp_path / "migration_no_start_failures.py"
    scenario.write_text(
        "import dataclasses, runpy\n"
        f"_s = runpy.run_path({str(SCENARIOS / 'migration.py')!r})['scenario']\n"
        "scenario = dataclasses.replace(_s, checker=dataclasses.replace(_s.checker, start_failures=0))\n"
    )
    assert main(["verify", str(scenario), "--deployer", "paper", "--continue", "--pytest", str(py), "--no-progress"]) == 1
    out = capsys.readouterr().out
    assert "VIOLATED errors-justified after 3 steps" in out and "   1. action move_base" in out, out
    (tmp_path / "early.py").write_text(EARLY)
    early = tmp_path / "test_early.py"
    early.write_text(re.sub(r"^DEPLOYER = .*$", f"DEPLOYER = {str(tmp_path / 'early.py') + ':react'!r}", py.read_text(), flags=re.M))
    run = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-k", "errors_justified"]
    assert subprocess.run([*run, str(py)], capture_output=True, text=True, cwd=tmp_path).returncode == 0  # the paper's bug: there
    res = subprocess.run([*run, str(early)], capture_output=True, text=True, cwd=tmp_path)
    assert res.returncode == 1 and "no longer violates errors-justified" in res.stdout, res.stdout
