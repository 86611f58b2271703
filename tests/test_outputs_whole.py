"""Outputs are whole or absent: what desmon prints reaches a slow reader in full while
the timer that polices a deployer's code keeps ticking, and writers that carry names
stay well-formed whatever a name holds."""

from __future__ import annotations

import io
import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from desmon.paths import WholeWrites, timer_held, write_whole

ROOT = Path(__file__).resolve().parent.parent
ENV = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
RUN = ["run", str(ROOT / "scenarios" / "coffee_shift.py"), "--until", "8000", "--json"]


def _desmon(args: list[str], *, slow: bool) -> tuple[bytes, int]:
    """desmon's stdout and exit code, its stdout read in 4 KiB chunks with a pause after each when ``slow``."""
    proc = subprocess.Popen([sys.executable, "-m", "desmon", *args], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, env=ENV, cwd=ROOT)
    assert proc.stdout is not None
    chunks = []
    while True:
        chunk = proc.stdout.read1(4096)
        if not chunk:
            break
        chunks.append(chunk)
        if slow:
            time.sleep(0.01)
    return b"".join(chunks), proc.wait(timeout=300)


def test_a_large_json_summary_reaches_a_slow_reader_whole():
    fast, code = _desmon(RUN, slow=False)
    assert code in (0, 1)
    assert len(fast) > 2 * 65536  # more than a pipe holds: the writer blocks while the timer ticks
    slow, slow_code = _desmon(RUN, slow=True)
    assert slow_code == code

    def timeless(out: bytes) -> bytes:  # (the run's wall time is the one figure that may differ, in value and width)
        return re.sub(rb'"wall_s": [0-9.eE+-]+', b'"wall_s": 0', out)

    assert len(timeless(slow)) == len(timeless(fast))
    fast_json, slow_json = json.loads(fast), json.loads(slow)
    fast_json.pop("wall_s"), slow_json.pop("wall_s")
    assert slow_json == fast_json


_TICKING = """
import signal, sys
sys.path.insert(0, {root!r})
from desmon.paths import WholeWrites
signal.signal(signal.SIGALRM, lambda *_: None)
signal.setitimer(signal.ITIMER_REAL, 0.05, 0.05)
out = WholeWrites(sys.stdout)
out.write("x" * 600000 + "\\n")
for i in range(20000):
    print("line", i, file=out)
out.flush()
signal.setitimer(signal.ITIMER_REAL, 0, 0)  # (finalizing resets the handler: no tick may come after)
"""


def test_every_write_is_whole_while_a_timer_ticks():
    script = _TICKING.format(root=str(ROOT))
    proc = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, env=ENV)
    assert proc.stdout is not None
    got = bytearray()
    while chunk := proc.stdout.read1(4096):
        got += chunk
        time.sleep(0.002)
    assert proc.wait(timeout=120) == 0
    lines = bytes(got).decode().split("\n")
    assert lines[0] == "x" * 600000
    assert lines[1:-1] == [f"line {i}" for i in range(20000)]


def test_write_whole_goes_through_a_stream_without_a_file_descriptor():
    out = io.StringIO()
    assert write_whole(out, "abc" * 5000) == 15000
    assert out.getvalue() == "abc" * 5000
    wrapped = WholeWrites(out)
    wrapped.write("d")
    wrapped.write("e" * WholeWrites.LARGE)
    assert out.getvalue().endswith("d" + "e" * WholeWrites.LARGE)
    assert wrapped.getvalue() == out.getvalue()  # everything else is the stream's


_HELD = """
import signal, sys, time
sys.path.insert(0, {root!r})
from desmon.paths import timer_held
seen = []
signal.signal(signal.SIGALRM, lambda *_: seen.append(1))
with timer_held():
    signal.setitimer(signal.ITIMER_REAL, 0.01)
    time.sleep(0.05)
    assert not seen, "the timer signal came while held"
    assert signal.SIGALRM in signal.sigpending()
assert seen == [1], "the held timer signal did not come after"
assert signal.SIGALRM not in signal.pthread_sigmask(signal.SIG_BLOCK, set())
"""


@pytest.mark.skipif(not hasattr(signal, "pthread_sigmask"), reason="signals cannot be blocked here")
def test_the_timer_signal_waits_while_held_and_arrives_after():
    # (in a process of one thread: where another thread takes the signal, only this thread's writes are spared)
    proc = subprocess.run([sys.executable, "-c", _HELD.format(root=str(ROOT))], capture_output=True, text=True, env=ENV, timeout=120)
    assert proc.returncode == 0, proc.stderr


# ------------------------------------------------------------------ several files: all or none
ANALYZE = ["analyze", str(ROOT / "scenarios" / "coffee_shift.py"), "-p", "faults=False", "--horizon", "60", "--no-progress"]


def _analyze_export(tmp_path: Path, capsys) -> tuple[int, str]:  # type: ignore[no-untyped-def]
    from desmon.cli import main

    code = main([*ANALYZE, "--export", str(tmp_path / "m.tra")])
    return code, capsys.readouterr().err


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no named pipes here")
def test_an_export_whose_companion_is_a_pipe_is_refused_before_any_work(tmp_path, capsys):
    os.mkfifo(tmp_path / "m.lab")
    code, err = _analyze_export(tmp_path, capsys)
    assert code == 2
    assert err.count("\n") == 1 and f"would write {tmp_path / 'm.lab'}, which is not a regular file" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.lab"]


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0, reason="permissions do not bind root")
def test_an_export_whose_companion_is_write_protected_is_refused_before_any_work(tmp_path, capsys):
    (tmp_path / "m.srew").write_text("old\n")
    (tmp_path / "m.srew").chmod(0o444)
    code, err = _analyze_export(tmp_path, capsys)
    assert code == 2
    assert err.count("\n") == 1 and f"would write {tmp_path / 'm.srew'}, which is write-protected" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.srew"]
    assert (tmp_path / "m.srew").read_text() == "old\n"


def test_a_rename_that_fails_half_way_puts_back_the_files_already_replaced(tmp_path, monkeypatch):
    import desmon.paths as paths

    names = [tmp_path / f"m.{s}" for s in ("tra", "sta", "lab", "srew")]
    names[0].write_text("old tra\n")
    names[1].write_text("old sta\n")
    real = os.replace
    calls = []

    def failing(src, dst):  # type: ignore[no-untyped-def]
        if str(src).endswith(".part"):
            calls.append(dst)
            if len(calls) == 3:
                raise PermissionError(13, "Permission denied", str(dst))
        return real(src, dst)

    monkeypatch.setattr(paths.os, "replace", failing)
    with pytest.raises(PermissionError):
        with paths.replacing_all(names) as files:
            for fh, name in zip(files, names):
                fh.write(f"new {name.suffix}\n")
    assert len(calls) == 3
    assert names[0].read_text() == "old tra\n" and names[1].read_text() == "old sta\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.sta", "m.tra"]  # no new file, nothing left over


def test_the_files_of_a_set_replace_their_namesakes_together(tmp_path):
    from desmon.paths import replacing_all

    names = [tmp_path / "a.tra", tmp_path / "a.sta"]
    names[0].write_text("old\n")
    with replacing_all(names) as files:
        files[0].write("new tra\n")
        files[1].write("new sta\n")
    assert [p.read_text() for p in names] == ["new tra\n", "new sta\n"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.sta", "a.tra"]


def test_an_output_name_of_any_legal_length_is_written(tmp_path, capsys):
    """A file system takes names of up to 255 bytes; the temporary file written beside
    the output first must fit too, whatever the output's name."""
    from desmon.cli import main

    for length in (240, 255):
        out = tmp_path / ("b" * (length - 4) + ".dot")
        assert main(["show", str(Path(__file__).resolve().parent.parent / "scenarios" / "coffee_handover.py"), "--format", "dot", "-o", str(out)]) == 0
        assert out.read_text().startswith("digraph")
        assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []
        capsys.readouterr()
