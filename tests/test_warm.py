"""The suite's commands in processes forked from a warm interpreter (tests/warm.py) are what
a user's ``desmon`` process is: the same exit code and outputs, nothing one command does
reaching the next, a timeout that ends the command, and an interpreter of its own where
the environment asks for one."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

import warm

ROOT = Path(__file__).resolve().parent.parent
COFFEE = str(ROOT / "scenarios" / "coffee_handover.py")


def _cold(args: list[str], cwd: Path, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "desmon", *args], cwd=cwd, env=env, capture_output=True, text=True, timeout=120)


@pytest.mark.parametrize(
    "args",
    [
        ["replay", COFFEE],  # exit 0, a report and a warning on stderr
        ["explain", COFFEE, "combined_slip_detector", "--at", "5"],
        ["verify", "nothing.py"],  # exit 2, one line
        ["verify", COFFEE, "--deployer", "paper", "--invariant", "nope"],  # argparse's own usage error
    ],
)
def test_a_command_exits_and_prints_as_in_a_process_started_for_it(tmp_path, args):
    hot, cold = warm.run(args, cwd=tmp_path, timeout=120), _cold(args, tmp_path)
    assert (hot.returncode, hot.stdout, hot.stderr) == (cold.returncode, cold.stdout, cold.stderr)
    assert hot.stdout or hot.stderr


def test_what_a_scenario_does_to_its_process_reaches_no_later_command(tmp_path):
    """A scenario file runs in the command's process: one that breaks desmon, changes
    directory and leaves a thread behind changes nothing the next command computes."""
    (tmp_path / "breaks.py").write_text(
        "import os, threading, desmon.cli, desmon.loader\n"
        "open('ran', 'w').close()  # in the command's directory\n"
        "desmon.cli.main = desmon.loader.load_scenario = None\n"
        "os.chdir('/')\n"
        "threading.Thread(target=lambda: None, daemon=True).start()\n"
    )  # (and defines no scenario: refused, exit 2)
    assert warm.run(["replay", "breaks.py"], cwd=tmp_path, timeout=120).returncode == 2
    assert (tmp_path / "ran").exists()
    again, cold = warm.run(["replay", COFFEE], cwd=tmp_path, timeout=120), _cold(["replay", COFFEE], tmp_path)
    assert (again.returncode, again.stdout, again.stderr) == (cold.returncode, cold.stdout, cold.stderr)


def test_a_command_over_its_timeout_is_ended_with_the_processes_it_started(tmp_path):
    marker = tmp_path / "helper.pid"
    (tmp_path / "hangs.py").write_text(
        "import os, subprocess, sys, time\n"
        f"helper = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(120)'])\n"
        f"open({str(marker)!r}, 'w').write(str(helper.pid))\n"
        "time.sleep(120)\n"
    )
    t0 = time.monotonic()
    with pytest.raises(subprocess.TimeoutExpired):
        warm.run(["replay", "hangs.py"], cwd=tmp_path, timeout=3)
    assert time.monotonic() - t0 < 30
    helper = int(marker.read_text())
    for _ in range(100):  # killed with the command's process group (a zombie until its parent is reaped)
        stat = Path(f"/proc/{helper}/stat")
        if not stat.exists() or stat.read_text().rsplit(")", 1)[1].split()[0] == "Z":
            break
        time.sleep(0.05)
    else:
        pytest.fail(f"process {helper}, started by the command, outlived its timeout")


def test_an_interpreter_setting_in_the_environment_gets_an_interpreter_of_its_own(tmp_path, monkeypatch):
    """A hash seed (or any PYTHON* variable other than this process's) is read as Python
    starts: such a command starts Python, where a forked child would keep the server's."""
    (tmp_path / "seed.py").write_text(f"open({str(tmp_path / 'hash.txt')!r}, 'w').write(str(hash('desmon')))\n")  # no scenario: exit 2
    env = {**os.environ, "PYTHONHASHSEED": "7"}
    assert warm.needs_fresh(env) and not warm.needs_fresh(None) and not warm.needs_fresh(dict(os.environ))
    assert warm.run(["replay", "seed.py"], cwd=tmp_path, env=env, timeout=120).returncode == 2
    seeded = subprocess.run([sys.executable, "-c", "print(hash('desmon'))"], env=env, capture_output=True, text=True).stdout.strip()
    assert (tmp_path / "hash.txt").read_text() == seeded
    monkeypatch.setenv("DESMON_TEST_COLD", "1")
    assert warm.needs_fresh(None)
