"""The wrench sensor: the scalar force along the slip axis (N, positive = up), sampled on a
fixed grid ``t = k / rate``.

A sample is the sensor's white noise (:func:`desmon.detectors.signals.noise.wrench_noise`)
plus the disturbance of the action context it falls in
(:func:`desmon.detectors.signals.contexts.context_force`) plus the load of any slip near it
(:func:`desmon.detectors.signals.slips.slip_force`). Two sources exist: the LWR's own
estimate (50 Hz, sigma 0.3 N, base inertia leaks in) and a wrist F/T sensor (100–1000 Hz,
sigma 0.05 N, weak coupling). Samples are rendered and cached in blocks of
``WRENCH_BLOCK``; faults (silent / zero / stuck) are applied on the way out.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from typing import Final, Sequence

import numpy as np

from desmon.detectors.signals.ahead import Ahead, RenderAhead
from desmon.detectors.signals.common import Arr, Params, Segment, SensorFault, SignalParams, WrenchBlock, WrenchSource, wrench_indices
from desmon.detectors.signals.contexts import trial_force
from desmon.detectors.signals.noise import STREAM_WRENCH, WRENCH_BLOCK, BlockStream, wrench_noise
from desmon.detectors.signals.slips import MissionSlip, slip_force
from desmon.errors import SignalError
from desmon.model.actions import HOLD, IDLE

#: Rendered wrench blocks kept per mission.
WRENCH_CACHE: Final = 8


@dataclass(frozen=True, slots=True)
class WrenchConfig:
    """A wrench source's sample rate (Hz), noise sigma (N) and base-inertia coupling."""

    source: str
    rate: float
    sigma: float
    coupling: float


def wrench_config(source: WrenchSource, rate: float | None, params: SignalParams) -> WrenchConfig:
    """Rate, noise and coupling of ``source`` (``"lwr_estimate"`` or ``"wrist_ft"``), checked."""
    if source == "lwr_estimate":
        cfg = WrenchConfig(source, 50.0 if rate is None else float(rate), params.force_noise_lwr, 1.0)
    elif source == "wrist_ft":
        cfg = WrenchConfig(source, 500.0 if rate is None else float(rate), params.force_noise_ft, params.ft_coupling_scale)
        if not 100.0 <= cfg.rate <= 1000.0:
            raise SignalError(f"wrench_rate {cfg.rate!r} Hz: a wrist_ft streams at 100-1000 Hz; pick a rate in that range")
    else:
        raise SignalError(f"wrench_source {source!r}: use 'lwr_estimate' or 'wrist_ft'")
    if not (cfg.rate > 0 and math.isfinite(cfg.rate)):
        raise SignalError(f"wrench_rate {cfg.rate!r} must be a positive number of Hz")
    return cfg


class WrenchSensor:
    """Deterministic wrench samples of one mission (see the module docstring)."""

    def __init__(
        self,
        seed: int,
        config: WrenchConfig,
        segments: Sequence[Segment],
        seg_params: Sequence[Params],
        slips: Sequence[MissionSlip],
        faults: Sequence[SensorFault],
        params: SignalParams,
    ) -> None:
        self.seed = seed
        self.config = config
        self.rate = config.rate
        self.segments = tuple(segments)
        self.seg_params = tuple(seg_params)
        self.slips = tuple(slips)
        self.faults = tuple(f for f in faults if f.sensor == "wrench")
        self.params = params
        self._seg_starts = np.array([s.start for s in self.segments])
        self._seg_ends = np.array([s.end for s in self.segments])
        self._noise = BlockStream(seed, STREAM_WRENCH)
        self._cache: dict[int, Arr] = {}
        #: per slip: the span of times its load is rendered for (a block reaching into it)
        self._slip_spans = tuple((float(sl.t_s[0]) - 1.5, float(sl.t_s[0]) + 2.0, sl) for sl in self.slips)
        #: the spans' starts and ends, and whether both ascend (slips in time order): then the
        #: spans a block reaches are one run of them, found by bisection
        self._span_lo = [lo for lo, _hi, _sl in self._slip_spans]
        self._span_hi = [hi for _lo, hi, _sl in self._slip_spans]
        self._spans_sorted = self._span_lo == sorted(self._span_lo) and self._span_hi == sorted(self._span_hi)
        #: per segment: whether it adds a force (hold and idle add none)
        self._forceful = tuple(s.context not in (HOLD, IDLE) for s in self.segments)
        #: the worker rendering ahead, while one runs (:meth:`start_ahead`), and what it gave
        self.ahead = Ahead()

    # ------------------------------------------------------------------ rendering ahead
    def ahead_blocks(self) -> list[int]:
        """The blocks up to the end of the last segment: what a worker rendering ahead renders
        (:mod:`desmon.detectors.signals.ahead`)."""
        end = float(self._seg_ends.max()) if self._seg_ends.size else 0.0
        return list(range(int(end * self.rate) // WRENCH_BLOCK + 1))

    def start_ahead(self) -> RenderAhead:
        """Fork a worker that renders this sensor's blocks ahead (stop it with :meth:`stop_ahead`)."""
        return self.ahead.start(self._render_ahead, self.ahead_blocks(), [(WRENCH_BLOCK,)])

    def stop_ahead(self) -> None:
        """Stop the worker rendering ahead, if one runs; from then on every block is rendered here."""
        self.ahead.stop()

    @property
    def ahead_taken(self) -> int:
        """Blocks taken from workers rendering ahead, over this sensor's life."""
        return self.ahead.taken

    def _render_ahead(self, group: list[int]) -> list[tuple[Arr]]:
        """A worker's render of whole blocks."""
        return [(self._render(b, b * WRENCH_BLOCK, (b + 1) * WRENCH_BLOCK),) for b in group]

    def _cached(self, b: int) -> Arr | None:
        """Block ``b`` if cached or rendered ahead (then cached), else None."""
        hit = self._cache.get(b)
        if hit is None:
            got = self.ahead.take(b)
            if got is not None:
                hit = got[0]
                self._keep(b, hit)
        return hit

    def _keep(self, b: int, values: Arr) -> None:
        if len(self._cache) >= WRENCH_CACHE:
            del self._cache[next(iter(self._cache))]
        self._cache[b] = values

    def _block(self, b: int) -> Arr:
        hit = self._cached(b)
        if hit is not None:
            return hit
        out = self._render(b, b * WRENCH_BLOCK, (b + 1) * WRENCH_BLOCK)
        self._keep(b, out)
        return out

    def _render(self, b: int, k0: int, k1: int) -> Arr:
        """Samples ``k0 .. k1 - 1`` of block ``b`` (``b * WRENCH_BLOCK <= k0 < k1 <= (b + 1) *
        WRENCH_BLOCK``): the block's noise (its first ``k1 - b * WRENCH_BLOCK`` normals, a prefix
        of the block's draws), the contexts and the slips near the block. Every kernel is
        elementwise in ``t``, and which slips count is decided on the whole block's span, so
        a sample reads the same bytes whichever range of its block is rendered."""
        base = b * WRENCH_BLOCK
        t = np.arange(k0, k1, dtype=np.int64) / self.rate
        val = wrench_noise(self.seed, b, self.config.sigma, k1 - base, self._noise)[k0 - base :]
        t_lo, t_hi = base / self.rate, (base + WRENCH_BLOCK - 1) / self.rate  # the block's span
        i0 = int(self._seg_ends.searchsorted(float(t[0]), side="right"))
        i1 = int(self._seg_starts.searchsorted(float(t[-1]), side="right"))
        for i in range(i0, i1):
            if not self._forceful[i]:
                continue
            s = self.segments[i]
            # only the samples inside the segment (t ascends): the force is elementwise in t
            # and outside the segment nothing is added (``val`` is this range's own array)
            lo = int(t.searchsorted(s.start, side="left"))
            hi = int(t.searchsorted(s.end, side="left"))
            if hi > lo:
                val[lo:hi] += trial_force(s.context, t[lo:hi] - s.start, self.seg_params[i], self.params, self.config.coupling)
        spans = self._slip_spans
        if self._spans_sorted:  # the spans with before <= t_hi and after >= t_lo, in order
            spans = spans[bisect.bisect_left(self._span_hi, t_lo) : bisect.bisect_right(self._span_lo, t_hi)]
        for before, after, sl in spans:
            if t_hi < before or t_lo > after:
                continue
            val = val + slip_force(t[None, :], sl.t_s, sl.sign, sl.grav, sl.params)[0]
        return val

    def _span(self, k0: int, k1: int) -> Arr:
        """Fault-free samples ``k0 .. k1 - 1`` (a request by time), a fresh array: of each block
        they touch, a cached block's slice or else only the samples asked for, rendered."""
        B = WRENCH_BLOCK
        parts = []
        for b in range(k0 // B, (k1 - 1) // B + 1):
            lo, hi = max(k0, b * B), min(k1, (b + 1) * B)
            hit = self._cached(b)
            parts.append(hit[lo - b * B : hi - b * B].copy() if hit is not None else self._render(b, lo, hi))
        return parts[0] if len(parts) == 1 else np.concatenate(parts)

    def clean(self, k: Arr) -> Arr:
        """Fault-free samples at grid indices ``k``."""
        out = np.empty(k.shape)
        if k.size == 0:
            return out
        if k.ndim == 1 and int(k[-1]) - int(k[0]) + 1 == k.size and bool((k[1:] > k[:-1]).all()):
            return self._span(int(k[0]), int(k[-1]) + 1)
        b0 = int(k[0]) // WRENCH_BLOCK
        if k.ndim == 1 and int(k.max()) // WRENCH_BLOCK == b0 and int(k.min()) // WRENCH_BLOCK == b0:
            return self._block(b0)[k - b0 * WRENCH_BLOCK]
        blocks = k // WRENCH_BLOCK
        for b in np.unique(blocks):
            sel = blocks == b
            out[sel] = self._block(int(b))[k[sel] - b * WRENCH_BLOCK]
        return out

    def at(self, index: Arr) -> WrenchBlock:
        """Samples for grid indices ``index`` (int array, >= 0), faults applied."""
        k = np.asarray(index, dtype=np.int64)
        t = k / self.rate
        v = self.clean(k)  # a fresh array
        if not self.faults and k.ndim == 1:
            return WrenchBlock(k.copy() if k is index else k, t, v)
        keep = np.ones(k.shape, dtype=bool)
        for f in self.faults:
            hit = (t >= f.start) & (t < f.end)
            if f.mode == "silent":
                keep &= ~hit
            elif f.mode == "zero":
                v = np.where(hit, 0.0, v)
            else:
                k_last = max(0, math.ceil(f.start * self.rate - 1e-9) - 1)
                v = np.where(hit, self.clean(np.array([k_last]))[0], v)
        return WrenchBlock(k[keep], t[keep], v[keep])

    def between(self, t0: float, t1: float) -> WrenchBlock:
        """All samples with ``t0 <= t < t1``."""
        k = wrench_indices(t0, t1, self.rate)  # consecutive indices, a new array
        if self.faults or not k.size:
            return self.at(k)
        return WrenchBlock(k, k / self.rate, self._span(int(k[0]), int(k[-1]) + 1))  # :meth:`at`'s bytes, its checks skipped
