"""Combined slip detector: rule-based fusion of force and tactile on a fixed tick ([P1], [CODE]).

At every tick ``t_act + m * tick`` (m = 0, 1, ...; default tick 30 ms) the detector
takes the most recent sample of each stream (zero-order hold; a sample older than the
stream's timeout counts as missing) and reports

* ``up``   if ``S_T >= theta_T`` and ``S_F >= theta_F``
* ``down`` if ``S_T >= theta_T`` and ``S_F <= -theta_F``.
"""

from __future__ import annotations

import math
from typing import Final

import numpy as np

from desmon.detectors.base import INACTIVE_STATUS, Alarm, DetectorState, DetectorStatus, check_threshold
from desmon.detectors.force import DEFAULT_THETA_F, ForceDetector
from desmon.detectors.signals import DOWN, UP
from desmon.detectors.tactile import DEFAULT_THETA_T, FlowHint, TactileDetector

__all__ = ["CombinedDetector", "zoh", "DEFAULT_TICK"]

DEFAULT_TICK: Final = 0.03
Arr = np.ndarray


def zoh(sample_t: Arr, values: Arr, valid: Arr, ticks: Arr, stale: float) -> tuple[Arr, Arr]:
    """Zero-order hold of ``values`` at ``ticks`` (latest sample with time <= tick, per row).

    ``sample_t``, ``values``, ``valid``: ``(n, K)`` with rows sorted in time; ``ticks``
    ``(M,)``. Returns ``(value (n, M), valid (n, M))``; no sample yet, or one older than
    ``stale``, is invalid.
    """
    n, k = sample_t.shape
    m = ticks.size
    if k == 0:
        return np.zeros((n, m)), np.zeros((n, m), dtype=bool)
    if n == 1:
        off = np.zeros((1, 1))
    else:
        span = float(max(sample_t.max(), ticks.max() if m else 0.0) - min(sample_t.min(), ticks.min() if m else 0.0)) + 10.0
        off = np.arange(n)[:, None] * span
    flat = (sample_t + off).ravel()
    q = (ticks[None, :] + off).ravel()
    pos = np.searchsorted(flat, q, side="right") - 1
    row = np.repeat(np.arange(n), m)
    ok = pos >= row * k
    pos = np.where(ok, pos, 0)
    age = q - flat[pos]
    good = ok & valid.ravel()[pos] & (age <= stale)
    return np.where(good, values.ravel()[pos], 0.0).reshape(n, m), good.reshape(n, m)


def _nan_to_num(a: Arr) -> Arr:
    """``np.nan_to_num(a)`` of a float array, written into ``a`` itself (the caller's own copy):
    NaN reads 0.0, infinities the largest finite values."""
    if np.isfinite(a).all():
        return a
    np.copyto(a, 0.0, where=np.isnan(a))
    big = np.finfo(a.dtype).max
    np.copyto(a, big, where=a == np.inf)
    np.copyto(a, -big, where=a == -np.inf)
    return a


def _nan_to_num1(x: float) -> float:
    """``float(np.nan_to_num(x))`` of one value."""
    if math.isnan(x):
        return 0.0
    if math.isinf(x):
        return float(np.finfo(float).max) if x > 0 else -float(np.finfo(float).max)
    return x


def _zoh1(carry: tuple[float, float, bool], t: Arr, s: Arr, v: Arr, ticks: Arr, stale: float) -> tuple[Arr, Arr]:
    """One-stream zero-order hold with a carried last sample (the streaming case of :func:`zoh`)."""
    pos = t.searchsorted(ticks, side="right") - 1
    if t.size and pos.size and pos[0] >= 0:  # a new sample at or before every tick (pos ascends): no carry
        val = _nan_to_num(s[pos])
        good = v[pos]
        good &= ticks - t[pos] <= stale
        return (val if good.all() else np.where(good, val, 0.0)), good
    return _zoh1_carried(carry, t, s, v, ticks, stale, pos)


def _zoh1_carried(carry: tuple[float, float, bool], t: Arr, s: Arr, v: Arr, ticks: Arr, stale: float, pos: Arr) -> tuple[Arr, Arr]:
    """:func:`_zoh1` through the carried sample at every tick (its general path); ``pos`` is
    each tick's last new sample (-1: none yet, the carried one holds)."""
    new = pos >= 0
    p = np.maximum(pos, 0)
    if t.size:
        st = np.where(new, t[p], carry[0])
        val = np.where(new, _nan_to_num(s[p]), carry[1])
        ok = np.where(new, v[p], carry[2])
    else:
        st = np.full(ticks.shape, carry[0])
        val = np.full(ticks.shape, carry[1])
        ok = np.full(ticks.shape, carry[2])
    good = ok & (ticks - st <= stale)
    return np.where(good, val, 0.0), good


def combined_mask(s_t: Arr, t_ok: Arr, s_f: Arr, f_ok: Arr, theta_t: float, theta_f: float) -> tuple[Arr, Arr]:
    """``(up, down)`` fusion masks at ticks."""
    both = t_ok & f_ok & (s_t >= theta_t)
    return both & (s_f >= theta_f), both & (s_f <= -theta_f)


class CombinedDetector:
    """Streaming combined detector (force + tactile fused every ``tick`` seconds).

    ``process(wrench_times, wrench_values, tactile_times, tactile_samples, until)``:
    the caller passes every sample with time <= ``until`` not passed before; ticks up to
    ``until`` are evaluated. Warm-up and tare follow the inner detectors (WARMING until
    both are OK); NO_INPUT if either input is missing. ``tactile_flow``: the tactile
    frames' flow worked out ahead (:meth:`TactileDetector.scores`).
    """

    #: the keyword hints :meth:`process` takes (the simulation passes those a stream offers)
    hints = ("tactile_flow",)

    def __init__(
        self,
        force_threshold: float = DEFAULT_THETA_F,
        tactile_threshold: float = DEFAULT_THETA_T,
        *,
        tick: float = DEFAULT_TICK,
        warmup_gating: bool = True,
        tare_window: float = 0.5,
        name: str = "combined",
    ) -> None:
        self.tick = check_threshold("tick", tick)
        self.force = ForceDetector(force_threshold, tare_window=tare_window)
        self.tactile = TactileDetector(tactile_threshold, warmup_gating=warmup_gating)
        self.name = name
        self._active = False
        self._t_act = 0.0
        self._next = 0
        self._f = (-1e9, 0.0, False)
        self._t = (-1e9, 0.0, False)
        self.status: DetectorStatus = INACTIVE_STATUS

    @property
    def active(self) -> bool:
        return self._active

    def activate(self, t: float) -> None:
        self._active = True
        self._t_act = float(t)
        self._next = 0
        self._f = (-1e9, 0.0, False)
        self._t = (-1e9, 0.0, False)
        self.force.activate(t)
        self.tactile.activate(t)
        self.status = DetectorStatus(DetectorState.WARMING, "warm_up", float(t))

    def deactivate(self) -> None:
        self._active = False
        self.force.deactivate()
        self.tactile.deactivate()
        self.status = INACTIVE_STATUS

    def _stream(self, carry: tuple[float, float, bool], t: Arr, s: Arr, v: Arr) -> tuple[Arr, Arr, Arr]:
        return (
            np.concatenate([[carry[0]], t])[None],
            np.concatenate([[carry[1]], np.nan_to_num(s)])[None],
            np.concatenate([[carry[2]], v])[None],
        )

    def process(
        self,
        wrench_times: Arr,
        wrench_values: Arr,
        tactile_times: Arr,
        tactile_samples: Arr,
        until: float,
        *,
        tactile_flow: FlowHint | None = None,
    ) -> tuple[Alarm, ...]:
        if not self._active:
            return ()
        ft, fs, fv = self.force.scores(wrench_times, wrench_values)
        tt, ts, tv = self.tactile.scores(tactile_times, tactile_samples, tactile_flow)
        self.force.check_input(until)
        self.tactile.check_input(until)
        last = math.floor((until - self._t_act) / self.tick + 1e-9)
        ticks = self._t_act + np.arange(self._next, last + 1) * self.tick
        ticks = ticks[ticks <= until]
        alarms: tuple[Alarm, ...] = ()
        if ticks.size:
            sf, okf = _zoh1(self._f, ft, fs, fv, ticks, self.force.timeout)
            st, okt = _zoh1(self._t, tt, ts, tv, ticks, self.tactile.timeout)
            up, down = combined_mask(st, okt, sf, okf, self.tactile.threshold, self.force.threshold)
            hit = (up | down).nonzero()[0]
            alarms = tuple(Alarm(float(ticks[i]), self.name, UP if up[i] else DOWN) for i in hit)
            self._next += ticks.size
        if ft.size:
            self._f = (float(ft[-1]), _nan_to_num1(float(fs[-1])), bool(fv[-1]))
        if tt.size:
            self._t = (float(tt[-1]), float(ts[-1]), bool(tv[-1]))
        fst, tst = self.force.status, self.tactile.status
        if fst.state is DetectorState.NO_INPUT or tst.state is DetectorState.NO_INPUT:
            bad = fst if fst.state is DetectorState.NO_INPUT else tst
            new = DetectorStatus(DetectorState.NO_INPUT, f"{'force' if bad is fst else 'tactile'}:{bad.reason}", bad.since)
        elif fst.state is DetectorState.WARMING or tst.state is DetectorState.WARMING:
            w = fst if fst.state is DetectorState.WARMING else tst
            new = DetectorStatus(DetectorState.WARMING, w.reason, w.since)
        else:
            new = DetectorStatus(DetectorState.OK, "", max(fst.since, tst.since))
        if new.state is not self.status.state or new.reason != self.status.reason:
            self.status = new
        return alarms
