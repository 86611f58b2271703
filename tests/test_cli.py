"""The command line as a user runs it: one-line errors, exit codes."""

import subprocess
import sys

from desmon.cli import main


def test_replay_prints_the_timeline_and_exits_zero(root, capsys):
    assert main(["replay", str(root / "scenarios" / "coffee_handover.py")]) == 0
    assert "t3 t=23s  device lwr_wrench fails" in capsys.readouterr().out


def test_explain_gives_every_reason_a_platform_is_rejected(root, capsys):
    assert main(["explain", str(root / "scenarios" / "coffee_handover.py"), "combined_slip_detector", "--at", "5"]) == 0
    out = capsys.readouterr().out
    assert "acceptable: torso_pc" in out
    assert "hand_pc: Capacity(memory >= 250 MB) fails: 70 MB free (capacity 320, used by tactile_slip_detector 150, load 100)" in out


def test_explain_for_an_unknown_graph_is_a_one_line_error(root, capsys):
    assert main(["explain", str(root / "scenarios" / "coffee_handover.py"), "sonar"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("desmon: error:") and "'sonar'" in err and err.count("\n") == 1


def test_a_missing_scenario_file_is_a_one_line_error_with_exit_2(capsys):
    assert main(["replay", "no/such/file.py"]) == 2
    assert "no such scenario file" in capsys.readouterr().err


def test_a_scenario_with_a_syntax_error_names_file_and_line(tmp_path, capsys):
    bad = tmp_path / "bad.py"
    bad.write_text("x = (\n")
    assert main(["replay", str(bad)]) == 2
    err = capsys.readouterr().err
    assert f"{bad}:1: syntax error" in err or f"{bad}:2: syntax error" in err


def test_a_scenario_without_a_scenario_object_says_how_to_define_one(tmp_path, capsys):
    empty = tmp_path / "empty.py"
    empty.write_text("x = 1\n")
    assert main(["replay", str(empty)]) == 2
    assert "defines no Scenario" in capsys.readouterr().err


def test_a_scenario_with_an_invalid_model_reports_the_model_error(tmp_path, capsys):
    bad = tmp_path / "cyclic.py"
    bad.write_text(
        "from desmon.model import RobotBuilder\n"
        "r = RobotBuilder()\n"
        "with r.rpsl.perception_graph('g') as g:\n"
        "    g.sensor('s', reads='force_sensor')\n"
        "    g.processing('a', inputs=['s', 'b'])\n"
        "    g.processing('b', inputs=['a'])\n"
    )
    assert main(["replay", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "invalid scenario" in err and "cycle" in err and "Traceback" not in err


def test_python_dash_m_desmon_works(root):
    out = subprocess.run([sys.executable, "-m", "desmon", "--help"], capture_output=True, text=True, check=True).stdout
    assert "verify" in out and "run" in out


def test_timeline_commands_refuse_a_scenario_without_a_scripted_timeline(root, capsys):
    assert main(["explain", str(root / "scenarios" / "platform_crash.py"), "combined_slip_detector", "--at", "12"]) == 2
    err = capsys.readouterr().err
    assert "has no scripted timeline" in err and "desmon run" in err and err.count("\n") == 1


def test_a_moment_before_the_timeline_is_refused(root, capsys):
    assert main(["explain", str(root / "scenarios" / "coffee_handover.py"), "combined_slip_detector", "--at", "-3"]) == 2
    assert "the timeline starts at t=0s" in capsys.readouterr().err


def test_an_unwritable_output_path_is_a_one_line_error_with_exit_2(root, tmp_path, capsys):
    out = tmp_path / "no" / "such" / "dir" / "x.json"
    assert main(["show", str(root / "scenarios" / "coffee_handover.py"), "--format", "json", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"desmon: error: -o {out}: directory {out.parent} does not exist") and "Traceback" not in err


def test_what_a_scenario_script_prints_goes_to_stderr_so_stdout_stays_parseable(root, tmp_path, capsys):
    chatty = tmp_path / "chatty.py"
    chatty.write_text(
        "import runpy\n"
        "print('building the coffee scenario ...')\n"
        f"scenario = runpy.run_path({str(root / 'scenarios' / 'coffee_handover.py')!r})['scenario']\n"
    )
    assert main(["show", str(chatty), "--at", "t1", "--format", "json"]) == 0
    out, err = capsys.readouterr()
    import json

    assert json.loads(out)["edges"] and "building the coffee scenario" in err


def test_a_real_ctrl_c_while_a_scenario_loads_still_interrupts(tmp_path, capsys):
    import signal

    slow = tmp_path / "slow.py"
    slow.write_text("import os, signal, time\nos.kill(os.getpid(), signal.SIGINT)\ntime.sleep(5)\n")
    # Ctrl-C as a terminal delivers it: Python's own handler. A suite started with SIGINT
    # ignored (nohup, `trap "" INT`) inherits SIG_IGN, and desmon rightly leaves an ignored
    # Ctrl-C ignored; so the handler is set for this test and put back after it.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        assert main(["replay", str(slow)]) == 130
    finally:
        signal.signal(signal.SIGINT, previous)
    assert capsys.readouterr().err == "desmon: interrupted\n"


def test_an_output_that_is_a_link_to_the_input_is_refused(tmp_path, capsys):
    trace = tmp_path / "run.jsonl"
    trace.write_text('{"t":0,"type":"run","horizon":10}\n')
    (tmp_path / "run.png").symlink_to(trace)
    assert main(["plot", str(trace), "-o", str(tmp_path / "run.png")]) == 2
    assert "is the input file being read" in capsys.readouterr().err
    assert trace.read_text() == '{"t":0,"type":"run","horizon":10}\n'


def test_an_output_is_replaced_only_once_complete(tmp_path):
    import pytest

    from desmon.paths import replacing

    old = tmp_path / "run.jsonl"
    old.write_text("the previous run\n")
    old.chmod(0o640)
    with pytest.raises(RuntimeError):
        with replacing(old) as fh:
            fh.write("half a new run")
            raise RuntimeError("the simulation failed")
    assert old.read_text() == "the previous run\n" and list(tmp_path.iterdir()) == [old]
    with replacing(old) as fh:
        fh.write("the new run\n")
    assert old.read_text() == "the new run\n" and old.stat().st_mode & 0o777 == 0o640


def test_help_of_a_command_exits_zero(capsys):
    assert main(["verify", "--help"]) == 0
    assert "--max-states" in capsys.readouterr().out


def test_no_command_prints_help_and_one_error_line(capsys):
    assert main([]) == 2
    out, err = capsys.readouterr()
    assert "COMMAND" in out and err.startswith("desmon: error: no command given") and err.count("\n") == 1


def test_version_is_the_installed_package_version(capsys):
    from importlib.metadata import version

    import desmon

    assert main(["--version"]) == 0
    assert capsys.readouterr().out == f"desmon {desmon.__version__}\n"
    assert desmon.__version__ == version("desmon")  # pyproject.toml and the package agree


def _subparsers():  # type: ignore[no-untyped-def]
    import argparse

    from desmon.cli import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return sub.choices


def test_every_help_shows_every_default_once():
    """A default (not None/False) appears as "(default: X)", written by the formatter only."""
    import argparse

    for name, p in _subparsers().items():
        text = " ".join(p.format_help().split())
        for a in p._actions:
            if not a.option_strings or a.default in (None, False, argparse.SUPPRESS):
                continue
            assert f"(default: {a.default})" in text, f"desmon {name} {a.option_strings[0]}"
            assert "default" not in (a.help or ""), f"desmon {name} {a.option_strings[0]} writes its default by hand"


def test_workers_under_the_auto_engine_runs_the_table_engine_with_a_note(root, capsys):
    path = str(root / "scenarios" / "two_detectors.py")
    assert main(["verify", path, "--workers", "2", "--no-progress"]) == 0
    out, err = capsys.readouterr()
    assert "engine: table" in out
    note, *warnings = err.splitlines()  # the note, then the scenario's warnings (its 'hold' has no rule)
    assert "--workers 2 not used" in note and "--engine direct --workers 2" in note
    assert warnings == [w for w in warnings if w.startswith("desmon: warning: risky action")]


def test_a_reader_that_stops_early_ends_the_command_quietly(root, tmp_path):
    """``desmon run ... | head``: the pipe's reader goes away (here at once), and desmon ends as a
    pipe's writer does (SIGPIPE's status), with no error line about a file it could not write."""
    err = tmp_path / "err.txt"
    done = subprocess.run(
        f"{sys.executable} -m desmon run scenarios/coffee_handover.py --no-progress 2>{err} | true",
        shell=True, cwd=root, capture_output=True, text=True, timeout=120,
    )
    assert done.returncode == 0
    assert "error" not in err.read_text() and "Traceback" not in err.read_text(), err.read_text()


def test_an_output_that_cannot_be_written_whole_leaves_the_file_there_was(root, tmp_path):
    """``verify --json``, ``--pytest`` and ``--plot`` write a temporary file and rename it: a
    write that fails half-way (here the file-size limit of the process) names the file and
    leaves the earlier one byte for byte."""
    import resource

    from desmon.paths import GENERATED_TEST_HEAD

    for flag, name in (("--json", "out.json"), ("--pytest", "test_out.py"), ("--plot", "out.png")):
        (tmp_path / flag[2:]).mkdir()
        target = tmp_path / flag[2:] / name
        earlier = (GENERATED_TEST_HEAD if flag == "--pytest" else "") + "the earlier file\n"  # (--pytest writes over its own only)
        target.write_text(earlier)
        done = subprocess.run(
            [sys.executable, "-m", "desmon", "verify", str(root / "scenarios" / "coffee_handover.py"), "--no-progress",
             "--deployer", "mutant:no-recheck", flag, str(target)],
            capture_output=True, text=True, timeout=120, cwd=tmp_path,
            preexec_fn=lambda: resource.setrlimit(resource.RLIMIT_FSIZE, (2048, 2048)),
        )
        err = done.stderr.strip().splitlines()
        assert done.returncode == 2 and err[-1] == f"desmon: error: {target}: cannot read or write: File too large; check the path", done.stderr
        assert target.read_text() == earlier and [p.name for p in target.parent.iterdir()] == [name]


def test_pytest_writes_over_a_test_it_wrote_never_over_another_file(root, tmp_path, capsys):
    """A file the scenario reads (not imports: runpy, open), a script of the user's: --pytest
    refuses it in one line and leaves it as it was; a test it wrote earlier it replaces."""
    from desmon.cli import main

    scenario = str(root / "scenarios" / "migration.py")
    mine = tmp_path / "mine.py"
    mine.write_text("print('a script of mine')\n")
    assert main(["verify", scenario, "--deployer", "paper", "--pytest", str(mine), "--no-progress"]) == 2
    assert "exists and is not a file desmon wrote for --pytest" in capsys.readouterr().err
    assert mine.read_text() == "print('a script of mine')\n"
    generated = tmp_path / "test_mig.py"
    for _ in range(2):  # written, then written over
        assert main(["verify", scenario, "--deployer", "paper", "--pytest", str(generated), "--no-progress"]) == 1
    assert generated.read_text().startswith('"""Generated by `desmon verify`')


def test_fuzz_leaves_nothing_in_the_working_directory(root, tmp_path):
    """Hypothesis's own cache (.hypothesis/) goes to a temporary folder while desmon fuzz runs."""
    import os

    env = {k: v for k, v in os.environ.items() if k != "HYPOTHESIS_STORAGE_DIRECTORY"}
    done = subprocess.run([sys.executable, "-m", "desmon", "fuzz", str(root / "scenarios" / "migration.py"), "--examples", "5", "--no-progress"],
                          capture_output=True, text=True, timeout=120, cwd=tmp_path, env=env)
    assert done.returncode == 0 and "passed: 5 sequences" in done.stdout, done.stdout + done.stderr
    assert list(tmp_path.iterdir()) == []


def test_run_json_records_how_the_command_line_changed_the_world(capsys):
    """Two summaries of one scenario run under different settings are told apart by their
    ``world`` (as desmon estimate's report records it), not only by figures that differ."""
    import json

    main(["run", "scenarios/cloud_offload.py", "-p", "hours=0.01", "--timing", "exponential", "--phases", "2", "--no-signals", "--json"])
    summary = json.loads(capsys.readouterr().out)
    assert summary["world"] == ["-p hours=0.01", "--timing exponential", "--phases 2", "--no-signals"]
    main(["run", "scenarios/cloud_offload.py", "-p", "hours=0.01", "--json"])
    assert json.loads(capsys.readouterr().out)["world"] == ["-p hours=0.01"]


def test_fuzz_draws_its_count_of_sequences_on_a_terminal_only(root, tmp_path):
    """Into a file or a pipe, stderr gets no run of carriage-return lines (as with desmon evaluate)."""
    done = subprocess.run([sys.executable, "-m", "desmon", "fuzz", str(root / "scenarios" / "migration.py"), "--examples", "100"],
                          capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert done.returncode == 0 and "passed: 100 sequences" in done.stdout, done.stdout + done.stderr
    assert "\r" not in done.stderr and "sequences" not in done.stderr, done.stderr
