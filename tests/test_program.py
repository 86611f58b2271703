"""The ``desmon`` program runs each command in a child process it watches (desmon/cli/program.py).

What the watching is for (code desmon runs ending the process with ``os._exit``) is in
the bad-input corpus (tests/bad_inputs/exit_os_exit_*); signals sent to the program or
its group reaching the command once are in tests/test_long_work.py (Ctrl-C to the group)
and tests/test_deployer_guard.py (Ctrl-C to the program's process); the program killed
with its group taking the command's processes along is in tests/test_warm.py. Here: the
shell's job control.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the program watches its command on Linux")


def _state(pid: int) -> tuple[str, int]:
    """(state letter, user+system clock ticks) of process ``pid``."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return fields[0], int(fields[11]) + int(fields[12])


def _children(pid: int) -> list[int]:
    return [int(c) for c in Path(f"/proc/{pid}/task/{pid}/children").read_text().split()]


def _until(check, seconds: float = 10.0) -> bool:  # type: ignore[no-untyped-def]
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        if check():
            return True
        time.sleep(0.02)
    return False


def test_ctrl_z_stops_the_command_and_fg_continues_it_to_the_same_result(tmp_path):
    """SIGTSTP to the job's process group (a terminal's Ctrl-Z): the command stops (its CPU
    time stands still) and the program after it; SIGCONT to the group (the shell's fg)
    continues both, and the command ends with the output it gives unstopped."""
    argv = [sys.executable, "-m", "desmon", "run", str(ROOT / "scenarios" / "robot_day.py"), "--render-ahead", "off", "--no-progress"]
    plain = subprocess.run(argv, capture_output=True, text=True, timeout=300, cwd=tmp_path)
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True, cwd=tmp_path)
    try:
        assert _until(lambda: bool(_children(proc.pid)) and _state(_children(proc.pid)[0])[1] > 50), "the command never got going"
        child = _children(proc.pid)[0]
        os.killpg(proc.pid, signal.SIGTSTP)
        assert _until(lambda: _state(child)[0] == "T" and _state(proc.pid)[0] == "T"), (_state(child), _state(proc.pid))
        ticks = _state(child)[1]
        time.sleep(0.5)
        assert _state(child) == ("T", ticks)
        os.killpg(proc.pid, signal.SIGCONT)
        out, err = proc.communicate(timeout=300)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert plain.returncode == 0 and proc.returncode == 0, err
    wall = re.compile(r"[0-9.]+ s wall")  # the one figure a stop changes
    assert wall.sub("", out) == wall.sub("", plain.stdout) and err == plain.stderr
