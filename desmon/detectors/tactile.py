"""Tactile slip detector: tactile flow from consecutive centres of pressure ([P1] eqs. 3-7, [CODE]).

The Alcazar-Barajas slip index of a pad is the centroid of the full 2-D convolution
of two consecutive frames, centred on the convolution grid. For non-negative frames
that centroid is the sum of the two frames' centroids, so with the centred centre of
pressure ``c[k] = (sum i P / sum P - (R-1)/2, sum j P / sum P - (C-1)/2)`` the index
is ``I[k] = c[k-1] + c[k]`` (tests compare it with a brute-force convolution). Then

* ``phi_n[k] = || I_n[k] - I_n[k-1] ||``            (flow magnitude, direction dropped)
* ``S_T[k] = sum_n E[P_n] phi_n / sum_n E[P_n]``     (intensity-weighted, in cells)

over the pads in contact whose flow is valid. A pad without contact has centre (0, 0)
(as in [CODE]), so a pad *touching* makes its centre jump from 0 to the contact point:
this contact-onset spike is why the tactile detector fires on every grasp ([P1]).
With warm-up gating (default) flows are valid only from the 3rd frame received after
activation (the index needs frames k-2..k); without it the history starts from zero
centres at activation, which fires at activation during a hold.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

import numpy as np

from desmon.detectors.base import INACTIVE_STATUS, Alarm, DetectorState, DetectorStatus, StreamingDetector, check_threshold
from desmon.detectors.signals import N_PADS, PAD_COLS, PAD_ROWS
from desmon.errors import SignalError

__all__ = [
    "FlowHint",
    "TactileDetector",
    "TactileState",
    "flow_ahead",
    "centred_cop",
    "slip_index",
    "tactile_scores",
    "DEFAULT_THETA_T",
    "WARMUP_FRAMES",
]

DEFAULT_THETA_T: Final = 0.5
WARMUP_FRAMES: Final = 3
Arr = np.ndarray
_ROWS = np.asarray(PAD_ROWS, dtype=float)
_CELLS = _ROWS * PAD_COLS
_ROW_MID = (_ROWS - 1) / 2
_COL_MID = (PAD_COLS - 1) / 2


def centred_cop(moments: Arr, out: Arr | None = None) -> tuple[Arr, Arr]:
    """Centred centre of pressure ``(..., 6, 2)`` (row, column) and contact mask ``(..., 6)``.

    Pads without contact get centre (0, 0). With ``out`` (shape ``(..., 6, 2)``) the centres
    are written there.
    """
    planes = np.empty((2,) + moments.shape[:-1])
    contact, _steady = _planar_cop(_planes(moments), planes)
    cop = np.empty(moments.shape[:-1] + (2,)) if out is None else out
    np.copyto(cop, np.moveaxis(planes, 0, -1))
    return cop, contact


def _planes(moments: Arr) -> Arr:
    """``moments`` ``(..., 6, 3)`` as three contiguous planes ``(3, ..., 6)`` (one transposing
    copy), so that elementwise steps on them run on contiguous arrays, not strided views."""
    return moments.reshape(-1, 3).T.copy().reshape((3,) + moments.shape[:-1])


def _planar_cop(planes: Arr, cop: Arr) -> tuple[Arr, list[int] | None]:
    """:func:`centred_cop` in planes: the centres of the moments' ``planes`` (:func:`_planes`)
    written into ``cop`` ``(2, ..., 6)`` (rows, then columns); returns the contact mask and
    :func:`_steady_off` of it (the same operations on the same values as strided views)."""
    s = planes[0]
    contact = s > 0
    safe = np.where(contact, s, 1.0)
    steady = _steady_off(contact)
    off = ~contact if steady is None else None
    for c, mid in ((0, _ROW_MID), (1, _COL_MID)):
        part = cop[c]
        np.divide(planes[1 + c], safe, out=part)
        part -= mid
        if off is not None:
            np.copyto(part, 0.0, where=off)
    for pad in steady or ():
        cop[..., pad] = 0.0
    return contact, steady


def _steady_off(contact: Arr) -> list[int] | None:
    """The pads without contact in every frame of ``contact`` ``(..., 6)`` (C order) if every frame
    has the same contact as the one before (the usual chunk: contact changes at a grasp or a
    release); else None. Zeroing those pads then zeroes every pad-frame without contact."""
    flat = contact.reshape(-1)
    if flat.size and not (flat[N_PADS:] == flat[:-N_PADS]).all():
        return None
    return [i for i, on in enumerate(flat[:N_PADS].tolist()) if not on]


def slip_index(prev_frame: Arr, frame: Arr) -> Arr:
    """Slip index (row, column) of one pad from two consecutive frames ``(R, C)`` via the CoP identity."""
    r, c = frame.shape
    out = np.zeros(2)
    for f in (prev_frame, frame):
        f = np.asarray(f, dtype=float)
        tot = f.sum()
        if tot > 0:
            out += [(f.sum(axis=1) @ np.arange(r)) / tot - (r - 1) / 2, (f.sum(axis=0) @ np.arange(c)) / tot - (c - 1) / 2]
    return out


@dataclass(frozen=True, slots=True)
class TactileState:
    """Carried state of the tactile flow per trial and pad: previous centre, previous index, contact run."""

    cop: Arr  # (n, 6, 2)
    index: Arr  # (n, 6, 2)
    run: Arr  # (n,) frames received since activation

    @staticmethod
    def initial(n: int) -> "TactileState":
        return TactileState(np.zeros((n, N_PADS, 2)), np.zeros((n, N_PADS, 2)), np.zeros(n, dtype=np.int64))


def tactile_scores(moments: Arr, state: TactileState, gating: bool = True) -> tuple[Arr, Arr, TactileState]:
    """Tactile slip signal ``S_T (n, K)`` and validity ``(n, K)`` of frames ``moments (n, K, 6, 3)``.

    The returned state continues the stream: splitting ``K`` into chunks gives
    bit-identical results.
    """
    n, k = moments.shape[:2]
    planes = _planes(moments)
    s = planes[0]
    if not s.any():  # no contact anywhere: nothing valid (same result as below, cheaper)
        if k == 0:
            return np.zeros((n, 0)), np.zeros((n, 0), dtype=bool), state
        z = np.zeros((n, N_PADS, 2))
        last_index = state.cop.copy() if k == 1 else z
        return np.zeros((n, k)), np.zeros((n, k), dtype=bool), TactileState(z, last_index, state.run + k)
    # the centred centres of pressure written after the carried one; then the slip indices
    # after the carried one; in planes (row, column) of (n, K + 1, 6), contiguous
    cop_ext = np.empty((2, n, k + 1, N_PADS))
    cop_ext[:, :, 0] = state.cop.transpose(2, 0, 1)
    contact, steady = _planar_cop(planes, cop_ext[:, :, 1:])
    idx_ext = np.empty_like(cop_ext)
    idx_ext[:, :, 0] = state.index.transpose(2, 0, 1)
    np.add(cop_ext[:, :, 1:], cop_ext[:, :, :-1], out=idx_ext[:, :, 1:])
    d = idx_ext[:, :, 1:] - idx_ext[:, :, :-1]
    d *= d  # x ** 2 is x * x
    phi = d[0] + d[1]
    np.sqrt(phi, out=phi)
    # past the warm-up in every frame if in the first (run ascends): the contact mask itself
    warm = not gating or int(state.run.min()) + 1 >= WARMUP_FRAMES
    if warm and steady is not None:  # the weights of the pads in contact throughout, 0 elsewhere
        w = s / _CELLS
        for pad in steady:
            w[..., pad] = 0.0
    else:
        run = state.run[:, None] + np.arange(1, k + 1)[None, :]  # frames since activation, this one included
        valid_pad = contact if warm else (contact & (run >= WARMUP_FRAMES)[..., None])
        w = np.where(valid_pad, s / _CELLS, 0.0)
    den = _pad_sum(w)
    phi *= w  # w * phi (a product does not depend on the order)
    num = _pad_sum(phi)
    valid = den > 0
    if valid.all():  # num / den everywhere (the masks select it whole)
        s_t = np.divide(num, den, out=num)
    else:
        s_t = np.where(valid, num / np.where(valid, den, 1.0), 0.0)
    if k:
        new = TactileState(
            cop_ext[:, :, -1].transpose(1, 2, 0).copy(), idx_ext[:, :, -1].transpose(1, 2, 0).copy(), np.minimum(state.run + k, 1 << 30)
        )
    else:
        new = state
    return s_t, valid, new


@dataclass(frozen=True, slots=True)
class FlowHint:
    """The tactile flow of a run of fault-free frames, worked out before it is asked for (by a
    worker rendering ahead, :mod:`desmon.detectors.signals.ahead`): ``values[i]`` is ``S_T`` of
    frame number ``first + i`` from that frame and the two before it in the stream, -1.0 where
    no pad is in contact (no valid flow), NaN where not worked out. Past the warm-up those are
    the very floats :func:`tactile_scores` gives a detector fed the same frames in order, so
    the detector takes them instead of working them out (:meth:`TactileDetector.scores`)."""

    first: int
    values: Arr

    def __post_init__(self) -> None:
        first = self.first
        if isinstance(first, bool) or not isinstance(first, (int, np.integer)) or first < 0:
            raise SignalError(f"flow hint first frame {first!r} must be a frame number (an integer >= 0)")
        try:
            values = np.asarray(self.values, dtype=float)
        except (TypeError, ValueError):
            raise SignalError(f"flow hint values of type {type(self.values).__name__}: pass one float per frame (a 1-D array)") from None
        if values.ndim != 1:
            raise SignalError(f"flow hint values of shape {values.shape}: pass one float per frame (a 1-D array)")
        object.__setattr__(self, "first", int(first))
        object.__setattr__(self, "values", values)


def _frozen(a: Arr) -> Arr:
    a.setflags(write=False)  # shared by every detector: a write would raise, not leak
    return a


#: a detector's flow state at activation, and the frame "before" its first (none: NaN)
_FRESH = TactileState(_frozen(np.zeros((1, N_PADS, 2))), _frozen(np.zeros((1, N_PADS, 2))), _frozen(np.zeros(1, dtype=np.int64)))
_NO_FRAME = _frozen(np.full((N_PADS, 3), np.nan))
#: the flow and validity of two frames in the warm-up
_NO_FLOW = _frozen(np.zeros(2))
_NOT_VALID = _frozen(np.zeros(2, dtype=bool))
#: the state :func:`flow_ahead` starts from: past the warm-up, so only the frames themselves count
_PAST_WARMUP = TactileState(np.zeros((1, N_PADS, 2)), np.zeros((1, N_PADS, 2)), np.full(1, WARMUP_FRAMES, dtype=np.int64))


def flow_ahead(moments: Arr, before: Arr | None = None) -> Arr:
    """:class:`FlowHint` values of consecutive frames ``moments`` ``(K, 6, 3)``, given the two
    frames ``before`` them (``(2, 6, 3)``), or without them NaN for the first two."""
    for name, a in (("moments", moments), ("before", before)):
        if a is not None and (not isinstance(a, np.ndarray) or a.ndim != 3 or a.shape[1:] != (N_PADS, 3)):
            raise SignalError(f"flow_ahead: {name} of shape {getattr(a, 'shape', type(a).__name__)}: pass frame moments (K, 6, 3)")
    if before is not None and before.shape[0] != 2:
        raise SignalError(f"flow_ahead: {before.shape[0]} frames before, need the 2 before the first")
    m = moments if before is None else np.concatenate([before, moments])
    s, valid, _ = tactile_scores(m[None], _PAST_WARMUP, True)
    out = np.where(valid[0], s[0], -1.0)
    if before is None:
        out[:2] = np.nan
        return out
    return out[2:]


def _pad_sum(x: Arr) -> Arr:
    """``x.sum(axis=-1)`` of ``x`` ``(n, K, 6)`` (C order), the same floats: numpy sums an axis of
    six as ``(((((0.0 + x0) + x1) + x2) + x3) + x4) + x5`` (a test pins it against numpy).
    Over many frames that order runs as six additions along the frames, cheaper than
    numpy's reduction, which loops over the frames with six pads each."""
    if x.shape[-2] < 64:
        return x.sum(axis=-1)
    acc = np.add(0.0, x[..., 0])
    for i in range(1, N_PADS):
        acc += x[..., i]
    return acc


class TactileDetector(StreamingDetector):
    """Streaming tactile slip detector (6 pads, moments or full frames as input).

    Alarm (direction ``None``) at every frame with ``S_T >= threshold`` (default 0.5
    cells). After :meth:`activate` the status is WARMING (``'warm_up'``) until some pad
    has a valid flow. NO_INPUT reasons: ``'no_samples'`` (no frame for ``timeout`` s),
    ``'stuck'`` (``stuck_frames`` identical non-zero frames), ``'no_contact'``
    (``stuck_frames`` all-zero frames: a dead sensor or nothing in the hand; either
    way no slip can be seen).
    """

    def __init__(
        self,
        threshold: float = DEFAULT_THETA_T,
        *,
        warmup_gating: bool = True,
        timeout: float = 0.25,
        stuck_frames: int = 5,
        name: str = "tactile",
    ) -> None:
        self.threshold = check_threshold("tactile threshold", threshold)
        self.warmup_gating = bool(warmup_gating)
        self.timeout = check_threshold("timeout", timeout)
        if int(stuck_frames) < 2:
            raise SignalError(f"stuck_frames {stuck_frames!r} must be an integer >= 2")
        self.stuck_frames = int(stuck_frames)
        self.name = name
        #: frames whose flow came from a :class:`FlowHint` (not worked out here), over the detector's life
        self.hinted = 0
        self._active = False
        self.status: DetectorStatus = INACTIVE_STATUS
        self._reset(0.0)

    def _reset(self, t: float) -> None:
        self._t_act = t
        self._state = _FRESH
        #: the state still to be worked out from the last two frames and the frames since
        #: activation (after frames whose flow came from a hint), or None
        self._lazy: tuple[Arr, int] | None = None
        #: one past the last frame number of hinted, consecutive frames just consumed (-1: none)
        self._hint_end = -1
        self._last_t = t
        self._last_m: Arr = _NO_FRAME
        self._run = 0
        self._seen_valid = False

    @staticmethod
    def _as_moments(samples: Arr) -> Arr:
        a = np.asarray(samples, dtype=float)
        if a.ndim >= 3 and a.shape[-3:] == (N_PADS, 14, PAD_COLS):
            from desmon.detectors.signals import frame_moments

            return frame_moments(a).reshape(-1, N_PADS, 3)
        if a.shape[-2:] != (N_PADS, 3):
            raise SignalError(
                f"tactile samples of shape {a.shape}: pass moments (K, 6, 3) or frames (K, 6, 14, 6)"
            )
        return a.reshape(-1, N_PADS, 3)

    def scores(self, times: Arr, samples: Arr, flow: FlowHint | None = None) -> tuple[Arr, Arr, Arr]:
        """Advance with new frames; return ``(times, S_T, valid)`` per frame. ``flow`` (the
        simulation's workers rendering ahead pass it) holds the flow of these very frames,
        fault-free and consecutive in the stream (:class:`FlowHint`)."""
        t = np.asarray(times, dtype=float).reshape(-1)
        m = self._as_moments(samples)
        if m.shape[0] != t.size:
            raise SignalError(f"tactile samples: {t.size} times but {m.shape[0]} frames; pass one time per frame")
        if flow is not None and not isinstance(flow, FlowHint):
            raise SignalError(f"tactile flow hint of type {type(flow).__name__}: pass a FlowHint or none")
        if flow is not None and flow.values.shape != (t.size,):
            raise SignalError(f"tactile flow hint of shape {flow.values.shape} for {t.size} frames; pass one value per frame or none")
        keep = t >= self._t_act
        if not keep.all():
            t, m, flow = t[keep], m[keep], None
        if t.size == 0:
            return t, np.zeros(0), np.zeros(0, dtype=bool)
        n = t.size
        # frames in the current run of identical frames, the last one included
        if n > 1 and not bool((m[-1] == m[-2]).all()):
            run_last = 1  # the last frame differs from the one before
        else:
            # frames repeating the one before (the first: the last of the previous call)
            same = np.empty(n, dtype=bool)
            same[0] = bool((m[0] == self._last_m).all())
            if n > 1:
                np.all((m[1:] == m[:-1]).reshape(n - 1, -1), axis=1, out=same[1:])
            changed = (~same).nonzero()[0]
            run_last = n - int(changed[-1]) if changed.size else self._run + n
        self._run = run_last
        self._last_m = m[-1].copy()
        self._last_t = float(t[-1])
        s, valid = self._flow(m, flow)
        self._seen_valid = self._seen_valid or bool(valid.any())
        if run_last >= self.stuck_frames:
            reason = "no_contact" if not (m[-1, :, 0] > 0).any() else "stuck"
            first_bad = n - 1 - (run_last - self.stuck_frames)
            self._set(DetectorState.NO_INPUT, reason, float(t[max(first_bad, 0)]))
        elif not valid[-1]:
            self._set(DetectorState.WARMING, "warm_up", float(t[-1]))
        else:
            bad = (~valid).nonzero()[0]
            self._set(DetectorState.OK, "", float(t[bad[-1] + 1] if bad.size else t[0]))
        return t, s, valid

    def _flow(self, m: Arr, hint: FlowHint | None) -> tuple[Arr, Arr]:
        """``S_T`` and validity of frames ``m`` ``(K, 6, 3)``, carrying the state: from ``hint``
        where it holds them (past the first two frames, or from the first when the frames
        before were hinted and consecutive with these and past the warm-up), else worked out."""
        n = m.shape[0]
        lazy = self._lazy
        since = lazy[1] if lazy is not None else int(self._state.run[0])
        # the two frames before these were fed here, fault-free (then a hint's values hold from the first)
        contiguous = hint is not None and hint.first == self._hint_end
        head = 0 if contiguous and since + 1 >= WARMUP_FRAMES else 2
        if hint is None or n < max(head + 1, 2) or np.isnan(hint.values[head:]).any():
            self._hint_end = hint.first + n if hint is not None and (n >= 2 or contiguous) else -1
            s, valid, self._state = tactile_scores(m[None], self.state, self.warmup_gating)
            self._lazy = None
            return s[0], valid[0]
        tail = hint.values[head:]
        s, valid = np.maximum(tail, 0.0), tail >= 0.0
        if head and self.warmup_gating and since + head < WARMUP_FRAMES:  # both in the warm-up: no flow
            s, valid = np.concatenate([_NO_FLOW, s]), np.concatenate([_NOT_VALID, valid])
        elif head:  # the first two frames from the state carried so far
            s0, v0, _ = tactile_scores(m[None, :head], self.state, self.warmup_gating)
            s, valid = np.concatenate([s0[0], s]), np.concatenate([v0[0], valid])
        self._hint_end = hint.first + n
        self._lazy = (m[-2:].copy(), min(since + n, 1 << 30))
        self.hinted += n - head
        return s, valid

    @property
    def state(self) -> TactileState:
        """The flow's carried state (:class:`TactileState`) after the frames consumed so far."""
        if self._lazy is not None:
            tail, run = self._lazy
            cop, _contact = centred_cop(tail)
            self._state = TactileState(cop[-1:].copy(), np.add(cop[-1:], cop[-2:-1]), np.full(1, run, dtype=np.int64))
            self._lazy = None
        return self._state

    def check_input(self, until: float) -> None:
        """Flag NO_INPUT ('no_samples') if no frame arrived within ``timeout`` before ``until``."""
        if self._active and until - self._last_t > self.timeout and self.status.state is not DetectorState.NO_INPUT:
            self._set(DetectorState.NO_INPUT, "no_samples", self._last_t + self.timeout)

    #: the keyword hints :meth:`process` takes (the simulation passes those a stream offers)
    hints = ("tactile_flow",)

    def process(self, times: Arr, samples: Arr, until: float | None = None, *, tactile_flow: FlowHint | None = None) -> tuple[Alarm, ...]:
        """Consume tactile frames (moments ``(K, 6, 3)`` or frames ``(K, 6, 14, 6)``) and return
        alarms; ``tactile_flow``: see :meth:`scores`."""
        if not self._active:
            return ()
        t, s, valid = self.scores(times, samples, tactile_flow)
        if until is not None:
            self.check_input(float(until))
        hit = (valid & (s >= self.threshold)).nonzero()[0]
        return tuple(Alarm(float(t[i]), self.name, None) for i in hit)
