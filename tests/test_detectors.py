"""Detectors: the CoP identity, streaming equivalence, warm-up, direction, invalid input."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from desmon.detectors.base import Alarm, DetectorState, merge_alarms
from desmon.detectors.combined import CombinedDetector
from desmon.detectors.force import ForceDetector
from desmon.detectors.signals import MissionSignals, SensorFault
from desmon.detectors.tactile import TactileDetector, slip_index
from desmon.errors import SignalError


def _full_convolution(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    m, n = a.shape
    out = np.zeros((2 * m - 1, 2 * n - 1))
    for i in range(m):
        for j in range(n):
            for k in range(m):
                for l in range(n):
                    out[i + k, j + l] += a[i, j] * b[k, l]
    return out


def _brute_force_index(prev: np.ndarray, cur: np.ndarray) -> np.ndarray:
    """[P1] eqs. 3-5 literally: centred means of the full 2-D convolution's row/column profiles."""
    c = _full_convolution(cur, prev)
    rows, cols = c.shape
    p = c.mean(axis=0)  # column profile
    q = c.mean(axis=1)  # row profile
    a = np.arange(cols) - (cols - 1) / 2
    b = np.arange(rows) - (rows - 1) / 2
    return np.array([q @ b / q.sum(), a @ p / p.sum()])


def test_cop_identity_equals_the_brute_force_full_convolution_slip_index() -> None:
    rng = np.random.default_rng(11)
    for rows in (14, 13):
        for _ in range(25):
            a = np.where(rng.random((rows, 6)) < 0.3, rng.integers(1, 600, (rows, 6)), 0).astype(float)
            b = np.where(rng.random((rows, 6)) < 0.3, rng.integers(1, 600, (rows, 6)), 0).astype(float)
            a[rng.integers(rows), rng.integers(6)] += 5
            b[rng.integers(rows), rng.integers(6)] += 5
            assert np.allclose(slip_index(a, b), _brute_force_index(a, b), atol=1e-12)


MISSION = [("grasp", 0.0, 2.0), ("hold", 2.0, 2.0), ("move_base", 4.0, 3.7), ("rotate_ccw", 7.7, 1.5),
           ("hold", 9.2, 2.0), ("release", 11.2, 1.2)]
SLIPS = [(3.0, "down", "pulled"), (10.0, "up", "pulled")]


def _feed_all(ms: MissionSignals, t_act: float, end: float) -> dict[str, tuple[Alarm, ...]]:
    f, t, c = ForceDetector(), TactileDetector(), CombinedDetector()
    for d in (f, t, c):
        d.activate(t_act)
    w, tb = ms.wrench(0.0, end), ms.tactile(0.0, end)
    return {
        "force": f.process(w.times, w.values, until=end),
        "tactile": t.process(tb.times, tb.moments, until=end),
        "combined": c.process(w.times, w.values, tb.times, tb.moments, until=end),
    }


def _feed_ticks(ms: MissionSignals, t_act: float, end: float, tick: float) -> dict[str, list[Alarm]]:
    f, t, c = ForceDetector(), TactileDetector(), CombinedDetector()
    for d in (f, t, c):
        d.activate(t_act)
    out: dict[str, list[Alarm]] = {"force": [], "tactile": [], "combined": []}
    a = 0.0
    while a < end:
        b = min(a + tick, end)
        w, tb = ms.wrench(a, b), ms.tactile(a, b)
        out["force"] += f.process(w.times, w.values, until=b)
        out["tactile"] += t.process(tb.times, tb.moments, until=b)
        out["combined"] += c.process(w.times, w.values, tb.times, tb.moments, until=b)
        a = b
    return out


@pytest.mark.parametrize("tick", [0.03, 0.0173, 0.5])
def test_block_and_tick_by_tick_processing_give_identical_alarms(tick: float) -> None:
    ms = MissionSignals(MISSION, SLIPS, seed=5)
    whole = _feed_all(ms, 0.0, 12.4)
    ticked = _feed_ticks(ms, 0.0, 12.4, tick)
    for name in whole:
        assert list(whole[name]) == ticked[name], name
    assert whole["force"] and whole["tactile"] and whole["combined"]


def test_same_seed_gives_identical_alarms() -> None:
    a = _feed_all(MissionSignals(MISSION, SLIPS, seed=9), 0.0, 12.4)
    b = _feed_all(MissionSignals(MISSION, SLIPS, seed=9), 0.0, 12.4)
    assert a == b


def test_warm_up_gating_removes_the_activation_false_alarm_that_appears_without_it() -> None:
    fired_cold = fired_gated = 0
    for seed in range(20):
        ms = MissionSignals([("grasp", 0.0, 2.0), ("hold", 2.0, 4.0)], [], seed=seed)
        tb = ms.tactile(3.0, 4.0)  # activate in the middle of a quiet hold
        cold = TactileDetector(warmup_gating=False)
        gated = TactileDetector()
        cold.activate(3.0)
        gated.activate(3.0)
        fired_cold += bool(cold.process(tb.times, tb.moments, until=4.0))
        fired_gated += bool(gated.process(tb.times, tb.moments, until=4.0))
    assert fired_cold >= 18 and fired_gated == 0


def test_force_direction_flips_for_a_gravitational_slip() -> None:
    for kind, expected in (("pulled", "down"), ("gravitational", "up")):
        hits = []
        for seed in range(10):
            ms = MissionSignals([("hold", 0.0, 4.0)], [(2.0, "down", kind)], seed=seed)
            w = ms.wrench(0.0, 4.0)
            det = ForceDetector()
            det.activate(0.0)
            alarms = [a for a in det.process(w.times, w.values, until=4.0) if 1.0 <= a.time <= 3.0]
            if alarms:
                hits.append(alarms[0].direction)
        assert hits and all(d == expected for d in hits), (kind, hits)


@pytest.mark.parametrize("mode", ["silent", "stuck", "zero"])
def test_a_wrench_sensor_failure_is_reported_as_no_input(mode: str) -> None:
    ms = MissionSignals([("hold", 0.0, 6.0)], [], seed=1, faults=[SensorFault("wrench", 3.0, mode)])
    f, c = ForceDetector(), CombinedDetector()
    f.activate(0.0)
    c.activate(0.0)
    for a in np.arange(0.0, 6.0, 0.03):
        w, tb = ms.wrench(a, a + 0.03), ms.tactile(a, a + 0.03)
        f.process(w.times, w.values, until=a + 0.03)
        c.process(w.times, w.values, tb.times, tb.moments, until=a + 0.03)
        if a < 2.9 and a > 1.0:
            assert f.status.valid and c.status.valid
    assert f.status.state is DetectorState.NO_INPUT and not f.status.valid
    assert f.status.reason == ("no_samples" if mode == "silent" else "stuck")
    assert c.status.state is DetectorState.NO_INPUT and c.status.reason.startswith("force:")


@pytest.mark.parametrize(("mode", "reason"), [("silent", "no_samples"), ("stuck", "stuck"), ("zero", "no_contact")])
def test_a_tactile_sensor_failure_is_reported_as_no_input(mode: str, reason: str) -> None:
    ms = MissionSignals([("hold", 0.0, 6.0)], [], seed=1, faults=[SensorFault("tactile", 3.0, mode)])
    t = TactileDetector()
    t.activate(0.0)
    tb = ms.tactile(0.0, 2.9)
    t.process(tb.times, tb.moments, until=2.9)
    assert t.status.valid
    tb = ms.tactile(2.9, 6.0)
    assert not t.process(tb.times, tb.moments, until=6.0)
    assert t.status.state is DetectorState.NO_INPUT and t.status.reason == reason


def test_force_detector_is_warming_during_its_tare_and_inactive_after_deactivation() -> None:
    ms = MissionSignals([("hold", 0.0, 2.0)], [], seed=1)
    f = ForceDetector()
    f.activate(0.0)
    w = ms.wrench(0.0, 0.3)
    f.process(w.times, w.values, until=0.3)
    assert f.status.state is DetectorState.WARMING and f.tare is None
    w = ms.wrench(0.3, 1.0)
    f.process(w.times, w.values, until=1.0)
    assert f.status.valid and f.tare is not None
    f.deactivate()
    assert f.status.state is DetectorState.INACTIVE and f.process(w.times, w.values) == ()


def test_detectors_accept_full_frames_as_well_as_moments() -> None:
    ms = MissionSignals(MISSION, SLIPS, seed=5)
    tb = ms.tactile(0.0, 12.4, frames=True)
    a, b = TactileDetector(), TactileDetector()
    a.activate(0.0)
    b.activate(0.0)
    assert a.process(tb.times, tb.moments) == b.process(tb.times, tb.frames)  # type: ignore[arg-type]


@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan"), "1.5", True])
def test_bad_thresholds_raise_a_signal_error(bad: object) -> None:
    with pytest.raises(SignalError):
        ForceDetector(bad)  # type: ignore[arg-type]
    with pytest.raises(SignalError):
        TactileDetector(bad)  # type: ignore[arg-type]


def test_alarms_are_frozen_slotted_records_and_debounce_merges_bursts() -> None:
    a = Alarm(1.0, "force", "up")
    assert not hasattr(a, "__dict__")
    with pytest.raises(dataclasses.FrozenInstanceError):
        a.time = 2.0  # type: ignore[misc]
    burst = [Alarm(1.0, "f", "up"), Alarm(1.2, "f", "up"), Alarm(1.6, "f", "up"), Alarm(2.2, "f", "down")]
    assert [x.time for x in merge_alarms(burst)] == [1.0, 2.2]


def test_force_and_tactile_share_one_activation_lifecycle() -> None:
    from desmon.detectors.base import DetectorState, StreamingDetector
    from desmon.detectors.force import ForceDetector
    from desmon.detectors.tactile import TactileDetector

    for cls, reason in ((ForceDetector, "tare"), (TactileDetector, "warm_up")):
        assert issubclass(cls, StreamingDetector)
        assert all(name not in cls.__dict__ for name in ("activate", "deactivate", "_set", "active"))
        d = cls()
        assert not d.active and d.status.state is DetectorState.INACTIVE
        d.activate(2.0)
        assert d.active and (d.status.state, d.status.reason, d.status.since) == (DetectorState.WARMING, reason, 2.0)
        d.deactivate()
        assert not d.active and d.status.state is DetectorState.INACTIVE
