"""Rendering ahead: a second process renders the tactile blocks, and nothing a user sees
changes but the wall time."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import threading
import time
from pathlib import Path

import numpy as np
import pytest
import warm
from conftest import deliveries

from desmon.detectors.signals import MissionSignals, SlipEvent, ahead
from desmon.detectors.tactile import TactileDetector
from desmon.errors import SignalError
from desmon.loader import load_scenario
from desmon.sim.engine import SimWorld

ROOT = Path(__file__).resolve().parents[1]

pytestmark = pytest.mark.skipif(not hasattr(os, "fork"), reason="rendering ahead forks")

#: a 22-minute mission: holds, moves and slips in every episode
_SEGS, _t = deliveries(30)
_SLIPS = [SlipEvent(s + 2.5, "down", "pulled") for c, s, _ in _SEGS if c == "hold"][::2]


def _pair() -> tuple[MissionSignals, MissionSignals]:
    return MissionSignals(_SEGS, _SLIPS, seed=9), MissionSignals(_SEGS, _SLIPS, seed=9)


def _requests(rng: np.random.Generator) -> list[tuple[float, float]]:
    """Requests by time as a detector makes them: chunks in order, a few jumps back and ahead."""
    out, t = [], 0.0
    while t < _t:
        d = float(rng.exponential(3.0))
        out.append((t, t + d))
        t += d if rng.random() > 0.05 else -d / 2
    return out


def _same(a, b) -> bool:  # type: ignore[no-untyped-def]
    return all(x.tobytes() == y.tobytes() for x, y in zip((a.index, a.times, a.moments), (b.index, b.times, b.moments)))


def test_frames_from_the_worker_are_the_frames_rendered_here() -> None:
    fast, ref = _pair()
    arr = fast.tactile_array
    worker = arr.start_ahead()
    pid = worker.pid
    try:
        for t0, t1 in _requests(np.random.default_rng(1)):
            assert _same(fast.tactile(t0, t1), ref.tactile(t0, t1)), (t0, t1)
        assert worker.taken > 0.8 * len(arr.ahead_blocks())
    finally:
        arr.stop_ahead()
    assert not worker.alive and arr.ahead_taken == worker.taken
    with pytest.raises(ChildProcessError):  # reaped: no zombie left
        os.waitpid(pid, os.WNOHANG)  # type: ignore[arg-type]


@pytest.mark.skipif(not hasattr(os, "SCHED_BATCH"), reason="Linux scheduling policies")
def test_a_worker_runs_as_a_batch_process_so_waking_it_never_preempts_the_simulation() -> None:
    fast, _ref = _pair()
    worker = fast.tactile_array.start_ahead()
    try:
        assert worker.pid is not None
        assert worker.take(worker.blocks[0]) is not None  # the worker is under way
        assert os.sched_getscheduler(worker.pid) == os.SCHED_BATCH
        assert os.sched_getscheduler(0) != os.SCHED_BATCH  # the simulation keeps its own
    finally:
        fast.tactile_array.stop_ahead()


def test_wrench_from_the_worker_is_the_wrench_rendered_here() -> None:
    fast, ref = _pair()
    sensor = fast.wrench_sensor
    worker = sensor.start_ahead()
    try:
        for t0, t1 in _requests(np.random.default_rng(4)):
            a, b = fast.wrench(t0, t1), ref.wrench(t0, t1)
            assert all(x.tobytes() == y.tobytes() for x, y in zip((a.index, a.times, a.values), (b.index, b.times, b.values))), (t0, t1)
        k = np.array([5, 3000, 7, 40_000, 1024, 1023])  # by index, out of order, across blocks
        assert fast.wrench_at(k).values.tobytes() == ref.wrench_at(k).values.tobytes()
        assert worker.taken > 0.8 * len(sensor.ahead_blocks())
    finally:
        fast.stop_ahead()
    assert sensor.ahead_taken == worker.taken and fast.ahead_taken == worker.taken


def test_blocks_the_simulation_goes_past_give_their_slots_back() -> None:
    # a block is copied out of its slot when taken; the slots of blocks never taken go back
    # before the simulation waits, so the worker never waits for a slot that nobody frees
    blocks = list(range(4 * ahead.SLOTS))
    worker = ahead.RenderAhead(lambda group: [(np.full(4, float(b)),) for b in group], blocks, [(4,)])
    try:
        t0 = time.perf_counter()
        for b in blocks[::3]:  # two blocks of three never taken
            got = worker.take(b)
            assert got is not None and got[0].tolist() == [float(b)] * 4
        assert worker.taken == len(blocks[::3]) and worker.missed == 0
        assert time.perf_counter() - t0 < ahead.STALL_S / 4  # no stall: the worker always had a slot
    finally:
        worker.close()


def test_a_mission_renders_the_wrench_ahead_only_when_asked() -> None:
    # a request by time renders only its own wrench samples; a worker would render every block
    fast, _ref = _pair()
    fast.start_ahead()
    try:
        assert fast.tactile_array.ahead.worker is not None and fast.wrench_sensor.ahead.worker is None
    finally:
        fast.stop_ahead()
    fast.start_ahead(wrench=True)
    try:
        assert fast.tactile_array.ahead.worker is not None and fast.wrench_sensor.ahead.worker is not None
    finally:
        fast.stop_ahead()
    with pytest.raises(SignalError, match="start_ahead: wrench 'yes' must be True or False"):
        fast.start_ahead(wrench="yes")  # type: ignore[arg-type]
    assert fast.tactile_array.ahead.worker is None  # nothing forked


def test_a_request_far_ahead_makes_the_worker_skip_there() -> None:
    fast, ref = _pair()
    arr = fast.tactile_array
    worker = arr.start_ahead()
    try:
        blocks = arr.ahead_blocks()
        late = blocks[-3] * 256 / arr.rate  # past the worker's first slots' worth of blocks
        assert blocks.index(blocks[-3]) > ahead.SLOTS
        assert _same(fast.tactile(late, late + 5.0), ref.tactile(late, late + 5.0))
        assert worker.taken >= 1
        assert _same(fast.tactile(1.0, 9.0), ref.tactile(1.0, 9.0))  # passed by the skip: rendered here
        assert worker.missed >= 1
    finally:
        arr.stop_ahead()


def test_a_worker_that_dies_leaves_the_run_to_render_alone() -> None:
    fast, ref = _pair()
    arr = fast.tactile_array
    worker = arr.start_ahead()
    reqs = _requests(np.random.default_rng(2))
    try:
        for i, (t0, t1) in enumerate(reqs):
            if i == len(reqs) // 3:
                os.kill(worker.pid, signal.SIGKILL)  # type: ignore[arg-type]
            assert _same(fast.tactile(t0, t1), ref.tactile(t0, t1)), (t0, t1)
        assert not worker.alive and worker.taken > 0
    finally:
        arr.stop_ahead()


def test_a_stalled_worker_is_given_up_after_the_stall_limit(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(ahead, "STALL_S", 0.2)
    fast, ref = _pair()
    arr = fast.tactile_array
    worker = arr.start_ahead()
    try:
        os.kill(worker.pid, signal.SIGSTOP)  # type: ignore[arg-type]
        time.sleep(0.05)
        late = arr.ahead_blocks()[-1] * 256 / arr.rate
        t0 = time.perf_counter()
        assert _same(fast.tactile(late, late + 3.0), ref.tactile(late, late + 3.0))
        assert time.perf_counter() - t0 < 10.0
        assert not worker.alive  # stopped, then killed and reaped
    finally:
        arr.stop_ahead()


def test_a_run_is_the_same_bytes_with_and_without_the_worker(monkeypatch: pytest.MonkeyPatch) -> None:
    sc = load_scenario(ROOT / "scenarios" / "robot_day.py")
    made: list[TactileDetector] = []  # every tactile detector of the runs (the combined ones' too)
    init = TactileDetector.__init__
    monkeypatch.setattr(TactileDetector, "__init__", lambda self, *a, **k: (init(self, *a, **k), made.append(self))[0])
    runs = []
    taken = []
    hinted = []
    for mode in (True, False):
        made.clear()
        w = SimWorld(sc, seed=3, until=1500.0, render_ahead=mode)
        r = w.run()
        runs.append((json.dumps(r.trace.records), r.metrics, [(a.time, a.detector) for a in r.alarms]))
        taken.append(w.bank.signals.ahead_taken)  # type: ignore[union-attr]
        hinted.append(sum(d.hinted for d in made))
    assert runs[0] == runs[1]
    assert taken[0] > 0 and taken[1] == 0
    assert hinted[0] > 0 and hinted[1] == 0  # the worker's tactile flow was taken, and changed no byte
    assert runs[0][2]  # the detectors saw frames and fired


def test_automatic_rendering_ahead_needs_a_long_run_and_a_lone_thread() -> None:
    sc = load_scenario(ROOT / "scenarios" / "robot_day.py")
    assert SimWorld(sc, until=7200.0)._ahead_wanted() is ahead.fork_safe()
    assert not SimWorld(sc, until=1500.0)._ahead_wanted()  # 962 s of object in hand: under AHEAD_MIN_S
    assert not SimWorld(sc, until=7200.0, render_ahead=False)._ahead_wanted()
    assert not SimWorld(sc, until=7200.0, signals=False, render_ahead=True)._ahead_wanted()  # nothing to render
    stop = threading.Event()
    th = threading.Thread(target=stop.wait)
    th.start()
    try:
        assert not ahead.fork_safe()  # another thread might hold a lock the fork would copy
    finally:
        stop.set()
        th.join()


def test_automatic_rendering_ahead_needs_a_graph_that_reads_the_tactile_frames(monkeypatch: pytest.MonkeyPatch) -> None:
    """A model whose graphs read only the wrench and a camera reads no tactile frame: a worker
    rendering them unasked would take a core for nothing. Asked, it still renders (the same bytes)."""
    import desmon.sim.engine as engine

    monkeypatch.setattr(engine, "fork_safe", lambda: True)  # as in a lone-thread process on 2 cores (not a test worker)
    pick = load_scenario(ROOT / "scenarios" / "pick_place_camera.py")
    assert not SimWorld(pick)._ahead_wanted()
    assert SimWorld(pick, render_ahead=True)._ahead_wanted()
    assert SimWorld(load_scenario(ROOT / "scenarios" / "coffee_shift.py"))._ahead_wanted()


def test_automatic_rendering_ahead_waits_for_a_run_whose_detectors_read_every_frame(monkeypatch: pytest.MonkeyPatch) -> None:
    """A run read only for figures no alarm far from a slip changes (the missed slips, the
    exposure) runs its detectors near the slips only: a worker rendering every second of
    holding would spend a core on blocks nobody takes. Asked, it still renders; the figures
    are the same either way."""
    import desmon.sim.engine as engine

    monkeypatch.setattr(engine, "fork_safe", lambda: True)  # as in a lone-thread process on 2 cores (not a test worker)
    shift = load_scenario(ROOT / "scenarios" / "coffee_shift.py")
    assert SimWorld(shift, reads=("false_alarms",))._ahead_wanted()
    assert not SimWorld(shift, reads=("slips_missed", "exposure_s"))._ahead_wanted()
    assert SimWorld(shift, reads=("slips_missed",), render_ahead=True)._ahead_wanted()
    reads = ("slips_missed", "exposure_s")
    figures = [SimWorld(shift, seed=3, until=2400.0, reads=reads, render_ahead=how).run().metrics for how in (None, True)]
    assert figures[0]["slips_missed"] == figures[1]["slips_missed"] and figures[0]["unmonitored_exposure_s"] == figures[1]["unmonitored_exposure_s"]


@pytest.mark.parametrize("value", ["yes", 1, 0.0, "auto"])
def test_render_ahead_takes_true_false_or_none(value: object) -> None:
    sc = load_scenario(ROOT / "scenarios" / "coffee_handover.py")
    with pytest.raises(SignalError, match=r"render_ahead .* must be True, False or None"):
        SimWorld(sc, render_ahead=value)  # type: ignore[arg-type]


def test_cli_render_ahead_is_checked_and_changes_no_output(tmp_path: Path) -> None:
    def run(*extra: str) -> subprocess.CompletedProcess[str]:
        return warm.run(["run", str(ROOT / "scenarios" / "robot_day.py"), "--until", "900", "--no-progress", "--json", *extra], cwd=ROOT, timeout=300)

    on = run("--render-ahead", "on", "--trace", str(tmp_path / "on.jsonl"))
    off = run("--render-ahead", "off", "--trace", str(tmp_path / "off.jsonl"))
    assert on.returncode == off.returncode == 0, on.stderr + off.stderr
    strip = lambda s: {k: v for k, v in json.loads(s).items() if "wall" not in k and k != "trace"}  # noqa: E731
    assert strip(on.stdout) == strip(off.stdout)
    # the workers write nothing: the trace (streamed to its file during the run) is the same bytes
    assert (tmp_path / "on.jsonl").read_bytes() == (tmp_path / "off.jsonl").read_bytes()
    # nothing on stderr but robot_day's warning about 'hold', which no rule covers
    assert on.stderr == off.stderr and on.stderr.startswith("desmon: warning: risky action 'hold'") and on.stderr.count("\n") == 1
    bad = run("--render-ahead", "sometimes")
    assert bad.returncode == 2 and "invalid choice: 'sometimes'" in bad.stderr and "Traceback" not in bad.stderr
    fleet = warm.run(["run", str(ROOT / "scenarios" / "fleet.py"), "--render-ahead", "on", "--no-progress"], cwd=ROOT, timeout=300)
    assert fleet.returncode == 2 and "drop --render-ahead" in fleet.stderr and "Traceback" not in fleet.stderr
    quiet = run("--render-ahead", "on", "--no-signals")
    assert quiet.returncode == 2 and "drop --render-ahead" in quiet.stderr and quiet.stderr.count("\n") == 1


def test_a_refused_fork_leaves_the_run_to_render_alone(monkeypatch: pytest.MonkeyPatch) -> None:
    def refuse() -> int:
        raise BlockingIOError(11, "Resource temporarily unavailable")

    fast, ref = _pair()
    monkeypatch.setattr(os, "fork", refuse)
    fast.start_ahead()  # no worker, no error
    assert fast.tactile_array.ahead.worker is None and fast.wrench_sensor.ahead.worker is None
    assert _same(fast.tactile(10.0, 60.0), ref.tactile(10.0, 60.0))


def test_a_process_that_ignores_sigchld_still_stops_its_workers(monkeypatch: pytest.MonkeyPatch) -> None:
    # with SIGCHLD ignored the kernel reaps the workers itself: stopping must not fail
    old = signal.signal(signal.SIGCHLD, signal.SIG_IGN)
    try:
        fast, ref = _pair()
        fast.start_ahead()
        assert _same(fast.tactile(10.0, 60.0), ref.tactile(10.0, 60.0))
        fast.stop_ahead()
        assert fast.tactile_array.ahead.worker is None and fast.ahead_taken > 0
    finally:
        signal.signal(signal.SIGCHLD, old)
