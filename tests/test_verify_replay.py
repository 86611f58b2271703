"""``desmon verify SCENARIO --replay cex.json``: a counterexample saved by ``--json`` re-run
through the real core, as a user who received the file would run it.

Exit 1 while the counterexample still violates its invariant (or no longer follows the
recorded states), 0 once it replays as recorded without the violation, 2 for bad input.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Callable

import pytest

from desmon.cli import main

ROOT = Path(__file__).resolve().parent.parent
MIGRATION = str(ROOT / "scenarios" / "migration.py")


def _steps(text: str) -> list[str]:
    """The numbered step lines of a report (``   0. initial -> ...``)."""
    return [line for line in text.splitlines() if line.lstrip()[:1].isdigit() and ". " in line and " -> " in line]


def _one_error_line(capsys: pytest.CaptureFixture[str]) -> str:
    """stderr of a refused command: exactly one ``desmon: error:`` line, no traceback."""
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("desmon: error: ") and "Traceback" not in err, err
    return err


@pytest.fixture
def saved(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> tuple[Path, str]:
    """migration.py's counterexamples with the paper deployer (--continue), and verify's report."""
    out = tmp_path / "cex.json"
    assert main(["verify", MIGRATION, "--deployer", "paper", "--continue", "--no-progress", "--json", str(out)]) == 1
    return out, capsys.readouterr().out


def _edited(src: Path, dst: Path, edit: Callable[[dict[str, Any]], None]) -> Path:
    data = json.loads(src.read_text())
    edit(data)
    dst.write_text(json.dumps(data))
    return dst


def _replay(path: Path, *extra: str, scenario: str = MIGRATION, deployer: str = "paper") -> int:
    return main(["verify", scenario, "--deployer", deployer, "--replay", str(path), *extra])


def test_a_saved_counterexample_still_violated_replays_its_steps_as_verify_printed_them_and_exits_1(saved, capsys):
    path, report = saved
    first = json.loads(path.read_text())["counterexamples"][0]
    assert _replay(path) == 1
    out = capsys.readouterr().out
    shown = _steps(out)
    assert shown and shown == _steps(report)[: len(shown)]  # the first counterexample, printed by verify's printer
    assert len(shown) == first["length"] + 1
    assert f"verdict: VIOLATED {first['invariant']}: the counterexample still holds, every state as recorded" in out
    assert f"{first['invariant']}" in out and f"VIOLATED: {first['message']}" in out


def test_counterexample_n_replays_the_files_nth_counterexample_with_its_failing_starts(saved, capsys):
    path, _report = saved
    written = json.loads(path.read_text())["counterexamples"]
    assert len(written) > 1 and any(s["fail_indices"] for c in written for s in c["states"])
    for n, c in enumerate(written, start=1):
        assert _replay(path, "--counterexample", str(n)) == 1
        out = capsys.readouterr().out
        assert f"counterexample {n} of {len(written)}" in out
        assert f"verdict: VIOLATED {c['invariant']}: the counterexample still holds, every state as recorded" in out


def test_an_instantaneous_violation_is_reproduced_inside_the_replayed_reaction(tmp_path, capsys):
    out = tmp_path / "mbb.json"
    mutant = "mutant:make-before-break"
    assert main(["verify", MIGRATION, "--deployer", mutant, "--no-progress", "--json", str(out)]) == 1
    capsys.readouterr()
    c = json.loads(out.read_text())["counterexamples"][0]
    assert c["during"]  # violated after a command, repaired by the end of the reaction
    assert _replay(out, deployer=mutant) == 1
    text = capsys.readouterr().out
    assert f"VIOLATED during the reaction, right after `{c['during']}`" in text
    assert f"verdict: VIOLATED {c['invariant']}: the counterexample still holds" in text


def test_replaying_with_the_corrected_deployer_is_refused_naming_both_deployers_and_the_fix(saved, capsys):
    path, _report = saved
    assert _replay(path, deployer="desmon") == 2
    err = _one_error_line(capsys)
    assert "--deployer paper" in err and "--deployer desmon" in err and "pass --deployer paper" in err


def test_a_fix_in_the_deployer_shows_as_no_longer_violated_but_diverged_and_exits_1(tmp_path, capsys):
    mine = tmp_path / "mine.py"
    mine.write_text('from desmon.verify.deployers import resolve_deployer\nMINE = resolve_deployer("paper")\n')
    spec = f"{mine}:MINE"
    out = tmp_path / "cex.json"
    assert main(["verify", MIGRATION, "--deployer", spec, "--no-progress", "--json", str(out)]) == 1
    c = json.loads(out.read_text())["counterexamples"][0]
    mine.write_text('from desmon.verify.deployers import resolve_deployer\nMINE = resolve_deployer("desmon")\n')  # the fix
    capsys.readouterr()
    assert _replay(out, deployer=spec) == 1
    text = capsys.readouterr().out
    assert "! step 0 diverges from" in text  # (the fix tries pc2 when the first reaction's start on pc1 fails)
    assert f"the counterexample no longer violates {c['invariant']}: fixed? But the replay diverged" in text


def test_a_counterexample_replayed_as_recorded_without_its_violation_exits_0_saying_fixed(saved, tmp_path, capsys):
    path, _report = saved

    def relabel(d: dict[str, Any]) -> None:  # as if the check of its invariant had been corrected: the run meets it
        d["counterexamples"][0].update(invariant="fixed")
        d["invariants"] = ["fixed"]

    relabelled = _edited(path, tmp_path / "relabelled.json", relabel)
    assert _replay(relabelled) == 0
    out = capsys.readouterr().out
    assert "verdict: the counterexample no longer violates fixed: fixed? (every state as recorded: the deployer did the same, " in out
    assert "so it is the check of fixed that changed since" in out and "or the file was edited)" in out
    assert "diverges" not in out


def test_a_replay_that_no_longer_violates_its_invariant_but_breaks_another_exits_1_naming_it(saved, tmp_path, capsys):
    """A file naming another invariant than its run breaks (edited): the replay's table shows
    the invariants it does break, and the verdict names them, exit 1 (it was "fixed?", exit 0)."""
    path, _report = saved
    broken = json.loads(path.read_text())["counterexamples"][0]["invariant"]
    relabelled = _edited(path, tmp_path / "relabelled.json", lambda d: d["counterexamples"][0].update(invariant="fixed"))
    assert _replay(relabelled) == 1
    out = capsys.readouterr().out
    verdict = next(line for line in out.splitlines() if line.startswith("verdict: "))
    assert verdict.startswith("verdict: VIOLATED ") and broken in verdict and "no longer violates fixed, but its replay violates" in verdict
    assert "fixed?" not in verdict


def test_a_replay_that_leaves_the_recorded_states_names_the_step_on_one_line_and_exits_1(saved, tmp_path, capsys):
    path, _report = saved

    def edit(d: dict[str, Any]) -> None:
        d["counterexamples"][0]["states"][1]["state"]["deployments"] = []

    assert _replay(_edited(path, tmp_path / "other.json", edit)) == 1
    out = capsys.readouterr().out
    [line] = [x for x in out.splitlines() if "diverges" in x]
    assert "step 1 diverges" in line and "deployments [] recorded" in line
    assert "although the replay diverged from the recorded run at step 1" in out


@pytest.mark.parametrize(
    "field, edit",
    [
        ("fail_indices", lambda c: c["states"][1].update(fail_indices=[-1])),
        ("event.kind", lambda c: c["states"][1]["event"].update(kind="device_explodes")),
        ("states", lambda c: c.update(states="none")),
        ("state", lambda c: c["states"][1].update(state=[1, 2])),
        ("invariant", lambda c: c.update(invariant="no-such-invariant")),
        ("fail_indices", lambda c: c["states"][1].update(fail_indices=[10**30], failed_starts=[])),
        ("fail_indices", lambda c: c["states"][1].update(fail_indices=[0, 0], failed_starts=["a", "b"])),
        ("states[0].event", lambda c: c["states"][0].update(event=c["states"][1]["event"])),
        ("length", lambda c: c.update(states=c["states"][:-1])),  # its last state cut: not a shorter path "fixed"
        ("length", lambda c: c.update(length=c["length"] + 3)),
        ("states[1].step", lambda c: c["states"][1].update(step=7)),
        ("length = missing", lambda c: (c.pop("length"), c.update(states=c["states"][:-1]))),  # cut, its length dropped
    ],
)
def test_a_hand_edited_bad_field_is_refused_on_one_line_naming_the_field(saved, tmp_path, capsys, field, edit):
    path, _report = saved
    bad = _edited(path, tmp_path / "bad.json", lambda d: edit(d["counterexamples"][0]))
    assert _replay(bad) == 2
    err = _one_error_line(capsys)
    assert str(bad) in err and field in err


def test_a_missing_file_a_directory_and_a_non_json_file_are_refused_on_one_line(tmp_path, capsys):
    text = tmp_path / "notes.json"
    text.write_text("VIOLATED, see the CI log\n")
    for given, says in ((tmp_path / "nope.json", "no such counterexample file"), (tmp_path, "is a directory"), (text, "not JSON")):
        assert _replay(given) == 2
        err = _one_error_line(capsys)
        assert str(given) in err and says in err


def test_a_counterexample_number_past_the_files_count_is_refused_naming_how_many_it_holds(saved, capsys):
    path, _report = saved
    count = len(json.loads(path.read_text())["counterexamples"])
    assert _replay(path, "--counterexample", str(count + 1)) == 2
    assert f"holds {count} counterexamples" in _one_error_line(capsys)


def test_a_file_of_another_scenario_is_refused_naming_both_scenarios(saved, capsys):
    path, _report = saved
    assert _replay(path, scenario=str(ROOT / "scenarios" / "two_detectors.py")) == 2
    err = _one_error_line(capsys)
    assert "'migration'" in err and "'two_detectors'" in err


def test_other_scenario_parameters_than_the_files_are_refused_naming_both(tmp_path, capsys):
    robot_day = str(ROOT / "scenarios" / "robot_day.py")
    out = tmp_path / "cex.json"
    assert main(["verify", robot_day, "--deployer", "paper", "-p", "hand_memory=512", "--no-progress", "--json", str(out)]) == 1
    capsys.readouterr()
    assert _replay(out, scenario=robot_day) == 2
    err = _one_error_line(capsys)
    assert "-p hand_memory=512" in err and "no -p parameters" in err
    assert _replay(out, "-p", "hand_memory=512", scenario=robot_day) == 1


def test_a_file_without_its_parameters_is_refused_not_replayed_unchecked(saved, tmp_path, capsys):
    """Without the "params" the run wrote, no -p given here could be checked against the
    file's: it is refused as edited, whatever -p the command gives."""
    path, _report = saved
    bare = _edited(path, tmp_path / "bare.json", lambda d: d.pop("params"))
    for given in ((), ("-p", "hand_memory=512")):
        assert _replay(bare, *given) == 2
        err = _one_error_line(capsys)
        assert str(bare) in err and "params = missing" in err


def test_a_file_without_counterexamples_is_refused_as_nothing_to_replay(tmp_path, capsys):
    out = tmp_path / "holds.json"
    assert main(["verify", MIGRATION, "--no-progress", "--json", str(out)]) == 0
    capsys.readouterr()
    assert _replay(out, deployer="desmon") == 2
    assert "holds no counterexample (verdict HOLDS)" in _one_error_line(capsys)


@pytest.mark.parametrize(
    "flag", [["--timeout", "5"], ["--engine", "direct"], ["--workers", "2"], ["--symmetry"], ["--continue"], ["--invariant", "coverage"]]
)
def test_a_search_option_given_with_replay_is_refused_naming_it(saved, capsys, flag):
    path, _report = saved
    assert _replay(path, *flag) == 2
    assert f"drop {flag[0]}" in _one_error_line(capsys)


def test_counterexample_without_replay_is_refused(capsys):
    assert main(["verify", MIGRATION, "--counterexample", "2"]) == 2
    assert "also give --replay FILE.json" in _one_error_line(capsys)


def test_plot_with_replay_draws_the_replayed_counterexample(saved, tmp_path, capsys):
    pytest.importorskip("matplotlib")
    path, _report = saved
    png = tmp_path / "replayed.png"
    assert _replay(path, "--plot", str(png)) == 1
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert f"wrote {png}" in capsys.readouterr().out


@pytest.mark.parametrize(
    "text", ['{"scenario": "migration", "seconds": 1' + "0" * 5000 + "}", "[" * 100_000 + "]" * 100_000],
    ids=["an integer of 5001 digits", "arrays nested 100,000 deep"],
)
def test_json_that_python_cannot_read_is_refused_on_one_line_not_a_traceback(tmp_path, capsys, text):
    odd = tmp_path / "odd.json"
    odd.write_text(text)
    assert _replay(odd) == 2
    err = _one_error_line(capsys)
    assert str(odd) in err and "not JSON" in err


def test_an_integer_too_large_for_a_float_in_a_saved_event_is_refused_on_one_line_naming_the_field(saved, tmp_path, capsys):
    def huge_load(data: dict[str, Any]) -> None:
        data["counterexamples"][0]["states"][1]["event"] = {"kind": "load", "platform": "pc1", "amount": 10**400}

    assert _replay(_edited(saved[0], tmp_path / "huge.json", huge_load)) == 2
    err = _one_error_line(capsys)
    assert "counterexamples[0].states[1].event" in err and "too large" in err


def test_a_file_naming_an_invariant_twice_is_refused_on_one_line(saved, tmp_path, capsys):
    path, _report = saved

    def twice(d: dict[str, Any]) -> None:
        d["invariants"] = d["invariants"] + d["invariants"][:1]

    bad = _edited(path, tmp_path / "twice.json", twice)
    assert _replay(bad) == 2
    err = _one_error_line(capsys)
    assert str(bad) in err and "twice" in err
