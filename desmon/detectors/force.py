"""Force slip detector: threshold on the tared slip-axis force, with direction ([P1] eqs. 1-2)."""

from __future__ import annotations

import math
from typing import Final

import numpy as np

from desmon.detectors.base import INACTIVE_STATUS, Alarm, DetectorState, DetectorStatus, StreamingDetector, check_threshold
from desmon.detectors.signals import DOWN, UP
from desmon.errors import SignalError

__all__ = ["ForceDetector", "force_alarm_mask", "tare_value", "DEFAULT_THETA_F"]

DEFAULT_THETA_F: Final = 1.5
Arr = np.ndarray


def tare_value(window: Arr) -> Arr:
    """Tare per trial: mean of the samples in the tare window, ``window (n, w)`` -> ``(n,)``."""
    if window.shape[-1] == 0:
        return np.mean(window, axis=-1)  # NaN, with numpy's warning
    # np.mean's own steps (its sum, then a division by the count) without its dispatch
    return np.add.reduce(window, axis=-1) / window.shape[-1]


def force_alarm_mask(scores: Arr, threshold: float) -> tuple[Arr, Arr]:
    """``(up, down)`` masks: ``S_F >= theta`` and ``S_F <= -theta``."""
    return scores >= threshold, scores <= -threshold


def _runs(same: Arr, run_prev: int) -> Arr:
    """Length of the current run of equal consecutive samples at each position (1 = new value)."""
    idx = np.arange(same.size)
    start = np.maximum.accumulate(np.where(~same, idx, -1))
    return np.where(start >= 0, idx - start + 1, run_prev + idx + 1)


class ForceDetector(StreamingDetector):
    """Streaming force slip detector.

    After :meth:`activate` at ``t`` the detector averages the samples in
    ``[t, t + tare_window)`` into the tare β (status WARMING, reason ``'tare'``), then
    scores every sample ``S_F = f - β``: ``up`` if ``S_F >= threshold``, ``down`` if
    ``S_F <= -threshold``. With ``tare_window = 0`` the first sample is the tare.
    Feed samples in time order with :meth:`process`; any chunking gives the same alarms.

    Invalid input is reported, never taken for "no slip": no sample for more than
    ``timeout`` s -> NO_INPUT ``'no_samples'``; ``stuck_samples`` identical consecutive
    values (a stuck or zeroed sensor; real noise never repeats exactly) -> NO_INPUT
    ``'stuck'`` and those samples are ignored.
    """

    WARMUP_REASON = "tare"

    def __init__(
        self,
        threshold: float = DEFAULT_THETA_F,
        *,
        tare_window: float = 0.5,
        timeout: float = 0.1,
        stuck_samples: int = 10,
        name: str = "force",
    ) -> None:
        self.threshold = check_threshold("force threshold", threshold)
        if not (tare_window >= 0 and math.isfinite(tare_window)):
            raise SignalError(f"tare_window {tare_window!r} must be >= 0 seconds")
        self.tare_window = float(tare_window)
        self.timeout = check_threshold("timeout", timeout)
        if int(stuck_samples) < 2:
            raise SignalError(f"stuck_samples {stuck_samples!r} must be an integer >= 2")
        self.stuck_samples = int(stuck_samples)
        self.name = name
        self._active = False
        self.status: DetectorStatus = INACTIVE_STATUS
        self._reset(0.0)

    def _reset(self, t: float) -> None:
        self._t_act = t
        self._buf: list[Arr] = []
        self._tare: float | None = None
        self._last_t = t
        self._last_v = math.nan
        self._run = 0

    @property
    def tare(self) -> float | None:
        """The current tare β (None while taring)."""
        return self._tare

    def scores(self, times: Arr, values: Arr) -> tuple[Arr, Arr, Arr]:
        """Advance the state with new samples; return ``(times, S_F, valid)`` per sample."""
        t = np.asarray(times, dtype=float).reshape(-1)
        v = np.asarray(values, dtype=float).reshape(-1)
        if t.shape != v.shape:
            raise SignalError(f"force samples: {t.size} times but {v.size} values; pass equal-length arrays")
        if t.size and t[0] < self._t_act:
            keep = t >= self._t_act
            t, v = t[keep], v[keep]
        if t.size == 0:
            return t, v, np.zeros(0, dtype=bool)
        same = np.empty(v.shape, dtype=bool)
        same[0] = v[0] == self._last_v
        np.equal(v[1:], v[:-1], out=same[1:])
        if self._tare is not None and not same.any():
            return self._tared_scores(t, v)
        return self._general_scores(t, v, same)

    def _general_scores(self, t: Arr, v: Arr, same: Arr) -> tuple[Arr, Arr, Arr]:
        """:meth:`scores` of samples ``t``, ``v`` at or after the activation (at least one),
        ``same[i]`` whether value ``i`` equals the one before it."""
        if not same.any():
            run = np.ones(v.shape, dtype=np.int64)
            good = np.ones(v.shape, dtype=bool)
        else:
            run = _runs(same, self._run)
            good = run < self.stuck_samples
        self._run = int(run[-1])
        self._last_v = float(v[-1])
        self._last_t = float(t[-1])
        s = np.full(t.shape, np.nan)
        valid = np.zeros(t.shape, dtype=bool)
        start = 0
        if self._tare is None:
            end_t = self._t_act + self.tare_window
            n_in = int(t.searchsorted(end_t, side="left"))
            self._buf.append(v[:n_in][good[:n_in]])
            start = n_in
            if n_in < t.size:
                window = np.concatenate(self._buf)
                if window.size:
                    self._tare = float(tare_value(window[None, :])[0])
                else:  # nothing in the window: the first good sample after it is the tare
                    first = np.flatnonzero(good[n_in:])
                    if first.size:
                        start = n_in + int(first[0]) + 1
                        self._tare = float(v[start - 1])
                    else:
                        start = t.size
                self._buf = []
        if self._tare is not None and start < t.size:
            s[start:] = v[start:] - self._tare
            valid[start:] = good[start:]
        if not good[-1]:
            self._set(DetectorState.NO_INPUT, "stuck", float(t[np.flatnonzero(good)[-1] + 1] if good.any() else t[0]))
        elif self._tare is None:
            self._set(DetectorState.WARMING, "tare", self._t_act)
        else:
            self._set(DetectorState.OK, "", float(t[start]) if self.status.state is not DetectorState.OK else self.status.since)
        return t, s, valid

    def _tared_scores(self, t: Arr, v: Arr) -> tuple[Arr, Arr, Arr]:
        """:meth:`scores` once tared, with no value equal to the one before: every sample valid,
        scored ``v - tare`` (the general path's steps without its masks and copies)."""
        self._run = 1
        self._last_v = float(v[-1])
        self._last_t = float(t[-1])
        tare = self._tare
        assert tare is not None
        self._set(DetectorState.OK, "", float(t[0]))  # since: kept if OK already (as _set does)
        return t, v - tare, np.ones(t.shape, dtype=bool)

    def check_input(self, until: float) -> None:
        """Flag NO_INPUT ('no_samples') if no sample arrived within ``timeout`` before ``until``."""
        if self._active and until - self._last_t > self.timeout and self.status.reason != "stuck":
            self._set(DetectorState.NO_INPUT, "no_samples", self._last_t + self.timeout)

    def process(self, times: Arr, values: Arr, until: float | None = None) -> tuple[Alarm, ...]:
        """Consume wrench samples (time order, all samples with time <= ``until``) and return alarms."""
        if not self._active:
            return ()
        t, s, valid = self.scores(times, values)
        if until is not None:
            self.check_input(float(until))
        up, down = force_alarm_mask(s, self.threshold)
        hit = (valid & (up | down)).nonzero()[0]
        return tuple(Alarm(float(t[i]), self.name, UP if up[i] else DOWN) for i in hit)
