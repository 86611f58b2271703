"""``desmon run`` shows its progress as one status line on stderr, rewritten in place
(``\\r``, as ``desmon verify`` and ``desmon sweep`` do), ended before anything else is
printed; stdout (the summary, ``--json``) is the same with or without it."""

from __future__ import annotations

import re

import pytest

from desmon.cli import main
from desmon.errors import SimulationError
from desmon.sim import engine
from desmon.cli import run as command
from desmon.cli.run import PROGRESS_PREFIX

WALL = re.compile(r"in [0-9.]+ s wall( \([0-9.]+x real time\))?")
#: a fleet summary's process peak memory, which a second run in the same process can raise
PEAK_RSS = re.compile(r"(peak memory \(RSS, MB\) +)[0-9.]+")


def _without_wall(text: str) -> str:
    return PEAK_RSS.sub(r"\1RSS", WALL.sub("in WALL", text))


HOLD_WARNING = "desmon: warning: risky action 'hold' has no selector rule"  # coffee_handover's hold: printed after the result


def _status_lines(err: str) -> list[str]:
    """The lines drawn on the status line: every ``\\r``-separated piece, padding removed (a warning line after it
    is not part of it)."""
    err, warning = err.split("\n" + HOLD_WARNING, 1) if HOLD_WARNING in err else (err, "")
    err += "\n" if warning else ""
    assert err.startswith("\r") and err.endswith("\n"), repr(err[:80])
    assert err.count("\n") == 1, "the progress was printed as separate lines"
    return [piece.rstrip() for piece in err[1:-1].split("\r")]


def _percent(line: str) -> float:
    return float(line.removeprefix(PROGRESS_PREFIX).split("%")[0])


def _run(capsys, *argv: str) -> tuple[int, str, str]:  # type: ignore[no-untyped-def]
    code = main(["run", *argv])
    cap = capsys.readouterr()
    return code, cap.out, cap.err


@pytest.fixture
def at_once(monkeypatch):  # type: ignore[no-untyped-def]
    """A run shows its progress from its first report (not only after a second of wall time)."""
    monkeypatch.setattr(command, "PROGRESS_AFTER", -1.0)


def test_a_run_rewrites_one_progress_line_in_place_and_ends_it(capsys, root, at_once):  # type: ignore[no-untyped-def]
    code, out, err = _run(capsys, str(root / "scenarios" / "coffee_handover.py"))
    assert code == 0
    lines = _status_lines(err)
    assert len(lines) > 1 and all(ln.startswith(PROGRESS_PREFIX) for ln in lines)
    percents = [_percent(ln) for ln in lines]
    assert percents == sorted(percents) and percents[-1] > 50


def test_a_runs_summary_on_stdout_is_the_same_with_the_progress_line(capsys, root, at_once):  # type: ignore[no-untyped-def]
    scenario = str(root / "scenarios" / "coffee_handover.py")
    _code, shown, err = _run(capsys, scenario, "--seed", "2")
    _code, quiet, quiet_err = _run(capsys, scenario, "--seed", "2", "--no-progress")
    assert err and quiet_err.startswith(HOLD_WARNING) and quiet_err.count("\n") == 1 and err.endswith(quiet_err)
    assert _without_wall(shown) == _without_wall(quiet)


def test_a_run_with_json_prints_no_progress_line(capsys, root, at_once):  # type: ignore[no-untyped-def]
    _code, out, err = _run(capsys, str(root / "scenarios" / "coffee_handover.py"), "--json")
    assert err.startswith(HOLD_WARNING) and err.count("\n") == 1 and out.startswith("{")  # the warning, no progress


def test_the_progress_line_is_ended_before_an_error_message(capsys, root, at_once, monkeypatch):  # type: ignore[no-untyped-def]
    class Crashing(engine.SimWorld):  # type: ignore[misc, valid-type]
        def run(self):  # type: ignore[no-untyped-def]
            self.progress(7.0, 28.0)
            raise SimulationError("the world broke")

    monkeypatch.setattr(engine, "SimWorld", Crashing)  # (desmon run imports it when it runs)
    code, out, err = _run(capsys, str(root / "scenarios" / "coffee_handover.py"))
    assert code == 2 and out == ""
    assert err == f"\r{PROGRESS_PREFIX} 25.0%  t=7/28 s\ndesmon: error: the world broke\n"


def test_a_fleet_run_rewrites_one_progress_line_in_place(capsys, root, at_once):  # type: ignore[no-untyped-def]
    fleet = [str(root / "scenarios" / "fleet.py"), "-p", "robots=2", "-p", "hours=0.2"]
    code, shown, err = _run(capsys, *fleet)
    assert code == 0
    lines = _status_lines(err)
    assert len(lines) > 1 and all(ln.startswith(PROGRESS_PREFIX) for ln in lines)
    _code, quiet, quiet_err = _run(capsys, *fleet, "--no-progress")
    assert quiet_err.startswith("desmon: warning: risky action 'hold' has no selector rule on 2 of the 2 robots")
    assert quiet_err.count("\n") == 1 and err.endswith(quiet_err)
    assert _without_wall(shown) == _without_wall(quiet)
