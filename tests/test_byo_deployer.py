"""Bring your own deployer: ``--deployer FILE.py:NAME``, ``module:NAME`` and ``mutant:NAME``
on every command, named as written, and every bad form one line with exit 2."""

from __future__ import annotations

import json
import sys
import textwrap
from pathlib import Path

import pytest

from desmon.cli import main
from desmon.deployment.deployer import DEPLOYERS, Deployer
from desmon.errors import ModelError
from desmon.verify.deployers import resolve_deployer
from desmon.verify.mutants import MUTANTS

ROOT = Path(__file__).resolve().parent.parent
COFFEE = str(ROOT / "scenarios" / "coffee_handover.py")
TWO = str(ROOT / "scenarios" / "two_detectors.py")

#: A correct deployer of one's own: the corrected reaction, re-exported under a new name.
CORRECT = """
from desmon.deployment.deployer import Deployer, make_desmon_react

MINE = Deployer("mine", "my corrected deployer", make_desmon_react())
"""

#: The same with a seeded bug: it reacts to context changes only (no re-check after a crash).
BUGGY = """
from desmon.deployment.deployer import make_desmon_react

_corrected = make_desmon_react()


def react(q, slots, changed, context_changed):
    \"\"\"my deployer, which forgets the platforms that changed\"\"\"
    if context_changed:
        yield from _corrected(q, slots, changed, context_changed)
"""


def _write(tmp_path: Path, name: str, text: str) -> str:
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return str(path)


@pytest.fixture(autouse=True)
def _keep_sys_path(monkeypatch: pytest.MonkeyPatch) -> None:
    """module:NAME puts the working directory on sys.path: undo it after each test."""
    monkeypatch.setattr(sys, "path", list(sys.path))


def test_a_correct_deployer_in_a_file_holds_and_is_named_as_written(tmp_path, capsys):
    spec = _write(tmp_path, "mine.py", CORRECT) + ":MINE"
    assert main(["verify", TWO, "--deployer", spec, "--no-progress", "--json", str(tmp_path / "r.json")]) == 0
    out = capsys.readouterr().out
    assert f"-- deployer {spec} --" in out and "verdict: HOLDS" in out and "states: 40 " in out
    assert json.loads((tmp_path / "r.json").read_text())["deployer"] == spec


def test_a_deployer_with_a_seeded_bug_gets_its_shortest_counterexample(tmp_path, capsys):
    spec = _write(tmp_path, "buggy.py", BUGGY) + ":react"
    assert main(["verify", COFFEE, "--deployer", spec, "--no-progress"]) == 1
    out = capsys.readouterr().out
    assert "VIOLATED valid-or-error after 2 steps" in out and f"deployer {spec}" in out


def test_a_reaction_function_is_wrapped_into_a_deployer_with_fallbacks(tmp_path):
    spec = _write(tmp_path, "buggy.py", BUGGY) + ":react"
    d = resolve_deployer(spec)
    assert isinstance(d, Deployer) and d.name == spec and d.fallbacks
    assert d.description == "my deployer, which forgets the platforms that changed"


@pytest.mark.parametrize("name", list(MUTANTS))
def test_every_mutant_is_selectable_as_mutant_colon_name(name):
    d = resolve_deployer(f"mutant:{name}")
    assert d.name == f"mutant:{name}" and d.react is MUTANTS[name].react
    assert d.stale_errors == MUTANTS[name].stale_errors


def test_the_mutant_form_on_the_command_line_finds_its_bug(capsys):
    assert main(["verify", COFFEE, "--deployer", "mutant:no-recheck", "--no-progress"]) == 1
    out = capsys.readouterr().out
    assert "-- deployer mutant:no-recheck --" in out and "VIOLATED valid-or-error after 2 steps" in out


def test_the_mutant_form_keeps_its_symmetry_reduction(capsys):
    path = str(ROOT / "scenarios" / "symmetric_platforms.py")
    assert main(["verify", path, "--deployer", "mutant:no-recheck", "--symmetry", "--no-progress"]) == 1
    assert "-- symmetry reduction" in capsys.readouterr().out


def test_built_in_names_still_resolve_to_the_built_in_deployers():
    for name, d in DEPLOYERS.items():
        assert resolve_deployer(name) is d


def test_module_colon_name_imports_from_the_working_directory(tmp_path, monkeypatch, capsys):
    _write(tmp_path, "my_deployers.py", CORRECT)
    monkeypatch.chdir(tmp_path)
    assert main(["verify", TWO, "--deployer", "my_deployers:MINE", "--no-progress"]) == 0
    assert "-- deployer my_deployers:MINE --" in capsys.readouterr().out


def test_every_command_takes_a_file_deployer_and_names_it(tmp_path, capsys):
    spec = _write(tmp_path, "mine.py", CORRECT) + ":MINE"
    assert main(["replay", COFFEE, "--deployer", spec]) == 0
    assert f"coffee_handover -- deployer {spec}" in capsys.readouterr().out
    assert main(["explain", COFFEE, "combined_slip_detector", "--at", "5", "--deployer", spec]) == 0
    assert f"({spec} deployer)" in capsys.readouterr().out
    assert main(["show", COFFEE, "--at", "t2", "--format", "json", "--deployer", spec]) == 0
    assert json.loads(capsys.readouterr().out)["edges"]
    trace = tmp_path / "run.jsonl"
    assert main(["run", COFFEE, "--deployer", spec, "--json", "--no-progress", "--trace", str(trace)]) == 0
    assert json.loads(capsys.readouterr().out)["deployer"] == spec
    assert json.loads(trace.read_text().splitlines()[0])["deployer"] == spec
    assert main(["fuzz", TWO, "--deployer", spec, "--examples", "5", "--no-progress"]) == 0
    assert f"-- deployer {spec} --" in capsys.readouterr().out


@pytest.mark.parametrize("source, spec", [("buggy.py", "buggy.py:react"), ("buggy_module.py", "buggy_module:react")], ids=["file", "module"])
def test_a_generated_pytest_replays_a_users_deployer_from_any_directory(tmp_path, monkeypatch, capsys, source, spec):
    """A file deployer is recorded by its absolute path; a module:NAME deployer is looked up
    where desmon verify ran first, and the generated test looks there first again."""
    import subprocess

    _write(tmp_path, source, BUGGY)
    monkeypatch.chdir(tmp_path)
    (tmp_path / "generated").mkdir()  # not beside the deployer (pytest puts a test's folder on the path)
    test = tmp_path / "generated" / "test_cex.py"
    assert main(["verify", COFFEE, "--deployer", spec, "--no-progress", "--pytest", str(test)]) == 1
    capsys.readouterr()
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    proc = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(test)], cwd=elsewhere, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout[-2000:]


def test_a_saved_counterexample_of_a_file_deployer_replays_from_any_directory(tmp_path, monkeypatch, capsys):
    """--json records the deployer's file by its absolute path: from another directory, the
    same file named by another relative path replays it, and so does the path the refusal
    of another deployer suggests."""
    (tmp_path / "dep").mkdir()
    _write(tmp_path / "dep", "buggy.py", BUGGY)
    monkeypatch.chdir(tmp_path)
    assert main(["verify", COFFEE, "--deployer", "dep/buggy.py:react", "--no-progress", "--json", "cex.json"]) == 1
    assert json.loads((tmp_path / "cex.json").read_text())["deployer"] == f"{tmp_path / 'dep' / 'buggy.py'}:react"
    capsys.readouterr()
    monkeypatch.chdir(tmp_path / "dep")
    assert main(["verify", COFFEE, "--deployer", "buggy.py:react", "--replay", "../cex.json"]) == 1
    assert "the counterexample still holds" in capsys.readouterr().out
    assert main(["verify", COFFEE, "--replay", "../cex.json"]) == 2
    suggested = capsys.readouterr().err.split("pass --deployer ")[1].split(" ")[0]
    assert main(["verify", COFFEE, "--deployer", suggested, "--replay", "../cex.json"]) == 1


BAD = {
    "no_colon": (None, "foo", "not a deployer; give one of paper, desmon, desmon-keep-fallback, mutant:NAME"),
    "file_without_name": (None, "mine.py", "name it: mine.py:NAME"),
    "missing_file": (None, "no/such/file.py:X", "no such file no/such/file.py"),
    "missing_module": (None, "no_such_module_xyz:X", "no module named 'no_such_module_xyz'"),
    "unknown_mutant": (None, "mutant:everything", "no mutant 'everything'; the mutants are mutant:no-recheck"),
    "empty_name": ("x = 1\n", "{f}:", "name the deployer after the colon"),
    "missing_attribute": (CORRECT, "{f}:YOURS", "has no 'YOURS'; it defines MINE"),
    "wrong_type": ("X = 3\n", "{f}:X", "X is an int, not a desmon.deployment.deployer.Deployer"),
    "wrong_signature": ("def react(q):\n    yield\n", "{f}:react", "cannot be called as react(q, slots, changed, context_changed)"),
    "never_yields": ("def react(q, slots, changed, context_changed):\n    return None\n", "{f}:react", "react never yields"),
    "raises": ("raise RuntimeError('no robot here')\n", "{f}:X", "raised RuntimeError: no robot here while imported"),
    "sys_exit": ("import sys\nsys.exit(4)\n", "{f}:X", "called sys.exit(4) while desmon imported it"),
    "system_exit_none": ("raise SystemExit\n", "{f}:X", "called sys.exit() while desmon imported it"),
    "imports_missing": ("import no_such_module_xyz\n", "{f}:X", "raised ModuleNotFoundError: No module named 'no_such_module_xyz'"),
    "syntax_error": ("x = (\n", "{f}:X", "syntax error"),
}


@pytest.mark.parametrize("case", list(BAD))
def test_a_bad_deployer_is_one_line_with_exit_2_before_any_work(case, tmp_path, monkeypatch, capsys):
    text, spec, expect = BAD[case]
    monkeypatch.chdir(tmp_path)
    if text is not None:
        spec = spec.format(f=_write(tmp_path, "dep.py", text))
    out = tmp_path / "r.json"
    assert main(["verify", COFFEE, "--deployer", spec, "--no-progress", "--json", str(out)]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and not out.exists()
    assert captured.err.startswith(f"desmon: error: --deployer {spec}: ") and captured.err.count("\n") == 1
    assert expect in captured.err and "Traceback" not in captured.err


def test_the_python_api_raises_a_model_error():
    with pytest.raises(ModelError, match="not a deployer"):
        resolve_deployer("fast")


@pytest.mark.parametrize("seconds", [-1, 0, float("nan"), float("inf"), "5", True])
def test_an_import_limit_that_is_no_positive_number_is_one_line(seconds):
    """``resolve_deployer(spec, import_seconds=...)``: how long the deployer's module may take
    to import in its worker process; anything but a finite number above 0 (or None) is refused."""
    from desmon.errors import ModelError
    from desmon.verify.deployers import resolve_deployer

    with pytest.raises(ModelError, match=r"import_seconds=.*: give the seconds its import may take, a number above 0, or None"):
        resolve_deployer(str(ROOT / "docs" / "examples" / "first_fit.py") + ":FIRST_FIT", import_seconds=seconds)


@pytest.mark.parametrize("says", ["call", "so it never ends"])  # (the second, the words of desmon's own limits)
def test_a_deployer_whose_state_makes_it_crash_is_refused_as_keeping_state_not_reported_crashed(tmp_path, capsys, says):
    """Its 150th reaction raises because of a counter it keeps: the direct engine reported
    CRASHED (at a state cap, and a VIOLATED at a depth cap whose replay said "fixed?"), with a
    path that does not crash again. The fresh re-run that refuses state kept between reactions now runs before
    a crash or a violation is reported, and at a state or depth cap too."""
    (tmp_path / "counting.py").write_text(textwrap.dedent('''
        from desmon.deployment.deployer import DESMON
        CALLS = [0]
        def counting(q, slots, changed, context_changed):
            CALLS[0] += 1
            if CALLS[0] == 150:  # (past the first transitions, each of which the search runs twice)
                raise RuntimeError(f"SAYS {CALLS[0]}")
            yield from DESMON.react(q, slots, changed, context_changed)
    ''').replace("SAYS", says))
    path = str(ROOT / "scenarios" / "coffee_handover.py")
    code = main(["verify", path, "--deployer", f"{tmp_path / 'counting.py'}:counting", "--engine", "direct", "--max-states", "100", "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2 and "is nondeterministic" in err and "CRASHED" not in capsys.readouterr().out, err


def test_the_errors_a_reaction_raises_cost_no_round_trip_and_change_no_answer(tmp_path, monkeypatch, capsys):
    """A reaction's RaiseError is sent to desmon without waiting for an answer (its outcome
    is always None and the error is booked when the reaction ends), so only Start and Stop
    are answered; errors sent in a row, and a reaction's end right behind them, are read in
    order: the corrected deployer run from a file gives the built-in one's search exactly."""
    from desmon.verify.isolation import Worker

    answered: list[object] = []
    send = Worker.send

    def counting(self, message):  # type: ignore[no-untyped-def]
        if message[0] == "sent":
            answered.append(message[1][0])  # the outcome desmon sends back
        return send(self, message)

    monkeypatch.setattr(Worker, "send", counting)
    spec = _write(tmp_path, "mine.py", CORRECT) + ":MINE"
    assert main(["verify", TWO, "--deployer", spec, "--engine", "direct", "--no-progress"]) == 0
    mine = capsys.readouterr().out
    assert main(["verify", TWO, "--engine", "direct", "--no-progress"]) == 0
    built_in = capsys.readouterr().out

    def search(out: str) -> list[str]:
        return [line.split("  time:")[0] for line in out.splitlines() if line.startswith(("verdict", "states:", "events", "selector", "deployer branches"))]

    assert search(mine) == search(built_in) and "error no_acceptable_platforms" in mine
    assert answered and all(type(outcome) is bool for outcome in answered)  # a Start's or a Stop's, never an error's
