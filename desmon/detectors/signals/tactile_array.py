"""The tactile array: six pads of pressure cells (``PAD_NAMES``; proximal pads 14 x 6 cells,
distal pads 13 x 6), read at about 30 Hz with jittered frame times.

Within an object-in-hand episode each touched pad sees a Gaussian pressure blob: its
amplitude, centre and spread come from the grasp contact
(:func:`desmon.detectors.signals.episodes.draw_contact`), are moved by the action
contexts (:func:`desmon.detectors.signals.contexts.context_tactile`, hold creep) and by
slips (:func:`desmon.detectors.signals.slips.slip_tactile`), see :func:`episode_pad_state`.
Cells whose noiseless value reaches the dead-band read ``clip(rint(mu + noise), 0, 3500)``.

:class:`TactileArray` renders a mission in blocks of ``TACTILE_BLOCK`` frames; block ``b``
draws its cell noise from the generator keyed ``(seed, tactile, b)`` in a fixed order
(episode by episode, pad by pad, frame by frame, cell by cell), so the bytes do not depend
on which blocks are rendered together. :func:`render_pad_moments` is the per-pad
reference of that order, :func:`render_rows` the vectorised form used for missions.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from typing import Callable, Final, Sequence

import numpy as np

from desmon.detectors.signals.common import (
    DEFAULT_PARAMS,
    FULL_SCALE,
    MAX_ROWS,
    N_PADS,
    PAD_COLS,
    PAD_ROWS,
    Arr,
    SensorFault,
    SignalParams,
    TactileBlock,
    tactile_nominal_indices,
    tactile_nominal_range,
)
from desmon.detectors.signals.ahead import Ahead, RenderAhead
from desmon.detectors.signals.contexts import context_tactile, hold_creep, move_base_tactile
from desmon.detectors.signals.episodes import Episode
from desmon.detectors.signals.noise import STREAM_TACTILE, BlockStream, Jitter, tactile_normals
from desmon.detectors.signals.slips import slip_tactile
from desmon.model.actions import HOLD, IDLE, MOVE_BASE

#: Frames per tactile render block.
TACTILE_BLOCK: Final = 256
#: ``frame >> _BLOCK_SHIFT`` is ``frame // TACTILE_BLOCK`` (a power of two)
_BLOCK_SHIFT: Final = TACTILE_BLOCK.bit_length() - 1
assert TACTILE_BLOCK == 1 << _BLOCK_SHIFT
#: Rendered tactile blocks kept per mission (a sim detector's quiet chunk spans ~4).
TACTILE_CACHE: Final = 16
#: Seconds of an object-in-hand episode rendered ahead of a tactile request.
PREFETCH_S: Final = 40.0

_ROW_OK: Final = np.arange(MAX_ROWS)[None, :] < np.asarray(PAD_ROWS)[:, None]  # (6, 14) cells that exist
_II: Final = np.arange(MAX_ROWS, dtype=float)
_JJ: Final = np.arange(PAD_COLS, dtype=float)
_PADS: Final = np.arange(N_PADS, dtype=np.int64)
#: flat cell -> ``i + j * 2**22``: a row's sum of ``value * code`` packs its moments ``sum i P``
#: (below 2**22) and ``sum j P``, exactly (integers below 2**53), for one reduction instead of two
_PACK: Final = float(2**22)
_CELL_CODE: Final = np.repeat(_II, PAD_COLS) + np.tile(_JJ, MAX_ROWS) * _PACK

#: A segment kernel's output over time as rows, and whether it is neutral before / after the segment.
_Term = tuple[Arr, bool, bool]
#: The term of an offset that is zero at every time and pad (what ``_term(np.zeros(1), 0.0)`` gives).
_ZERO_TERM: Final = (np.zeros((1, 1)), True, True)
_ZERO_TERM[0].flags.writeable = False
#: One rendered block: frame times ``(B,)``, moments ``(B, 6, 3)``, frames ``(B, 6, 14, 6)`` or None.
Rendered = tuple[Arr, Arr, "Arr | None"]


class _Scratch:
    """Work arrays a :class:`TactileArray` reuses from render to render: a render's largest
    arrays (per cell, per frame) are written into them instead of into fresh memory, which
    the allocator hands back to the system after each render and the next one faults in
    again, page by page."""

    __slots__ = ("_bufs",)

    def __init__(self) -> None:
        self._bufs: dict[str, Arr] = {}

    def get(self, name: str, n: int, dtype: type) -> Arr:
        """The first ``n`` elements of work array ``name`` (contents undefined), grown if shorter."""
        buf = self._bufs.get(name)
        if buf is None or buf.size < n:
            buf = np.empty(max(n, buf.size + buf.size // 4 if buf is not None else n), dtype)
            self._bufs[name] = buf
        return buf[:n]

    def arange(self, n: int) -> Arr:
        """``np.arange(n)`` (int64), read only: a view of one kept, grown if shorter."""
        buf = self._bufs.get("arange")
        if buf is None or buf.size < n:
            buf = np.arange(max(n, buf.size + buf.size // 4 if buf is not None else n), dtype=np.int64)
            self._bufs["arange"] = buf
        return buf[:n]


def episode_pad_state(t: Arr, ep: Episode, p: SignalParams) -> tuple[Arr, Arr, Arr]:
    """Amplitude, row centre and column centre of every pad, each ``(n, K, 6)``, at times ``t`` ``(n, K)``."""
    c = ep.contact
    amp = np.broadcast_to(c["A"][:, None, :], t.shape + (N_PADS,)).copy()
    yc = np.broadcast_to(c["y"][:, None, :], amp.shape).copy()
    xc = np.broadcast_to(c["x"][:, None, :], amp.shape).copy()
    t3 = t[..., None]
    ascending = t.shape[0] == 1 and bool(np.all(t[0, 1:] >= t[0, :-1]))
    for context, start, dur, cp in ep.segments:
        tr = np.clip(t3 - start, 0.0, dur)
        if context == HOLD:
            amp *= hold_creep(tr, c["kappa"], p)
            continue
        if context == IDLE:
            continue
        if ascending:
            _apply_context(context, tr, dur, cp, p, amp, yc, xc)
            continue
        fac, dy, dx = context_tactile(context, tr, cp, p)
        amp *= fac
        yc += dy
        xc += dx
    for t_s, sign, sp in ep.slips:
        fac, dy = slip_tactile(t3, t_s, sign, sp, p)
        amp *= fac
        yc += dy
    inside = ((t3 >= ep.start) & (t3 < ep.end))
    return np.where(inside, amp, 0.0), yc, xc


def _apply_context(context: str, tr: Arr, dur: float, cp: dict, p: SignalParams, amp: Arr, yc: Arr, xc: Arr) -> None:
    """``amp *= fac; yc += dy; xc += dx`` of :func:`context_tactile` at the clipped times
    ``tr`` ``(1, K, 1)``, ascending: the frames before the segment (``tr`` 0) and after it
    (``tr`` ``dur``) share one value each, so the kernel (exact arithmetic only: the same
    value for the same ``tr``) is evaluated on one frame of each and on the frames inside."""
    line = tr[0, :, 0]
    lo = int(np.searchsorted(line, 0.0, side="right"))  # frames before the segment: tr 0
    hi = max(lo, int(np.searchsorted(line, dur, side="left")))  # from here on: tr dur
    # (frames a..b, where their values are in the kernel's input): one kernel call
    parts = []
    m = 0
    for a, b, constant in ((0, lo, True), (lo, hi, False), (hi, line.size, True)):
        if b > a:
            n = 1 if constant else b - a
            parts.append((a, b, m, m + n))
            m += n
    sub = tr[:, parts[0][0] : parts[0][0] + m] if len(parts) == 1 else np.concatenate([tr[:, a : a + (e - s)] for a, _b, s, e in parts], axis=1)
    out = context_tactile(context, sub, cp, p)
    for a, b, s, e in parts:
        fac, dy, dx = (x[:, s:e] if x.ndim == 3 and x.shape[1] == m else x for x in out)
        amp[:, a:b] *= fac
        yc[:, a:b] += dy
        xc[:, a:b] += dx


def _segment_kernel(tt: Arr, lo: int, hi: int, seg: tuple[str, float, float, dict], kappa: Arr, p: SignalParams) -> tuple[_Term | None, ...]:
    """One segment's ``(fac, dy, dx)`` (``dy``, ``dx`` None for a hold: it moves no centre), each
    as rows over ``m + 2`` times: row 0 at ``tr = 0`` (the frames before the segment), rows
    ``1..m`` at the clipped times of frames ``lo..hi-1``, row ``m + 1`` at ``tr = dur`` (the
    frames after it). A row has 6 pads or 1 (the same for every pad); a term the same for
    every time has one row."""
    context, start, dur, cp = seg
    m = hi - lo
    arg = np.empty(m + 2)
    arg[0] = 0.0
    arg[m + 1] = dur
    inner = arg[1 : m + 1]
    np.subtract(tt[lo:hi], start, out=inner)
    inner.clip(0.0, dur, out=inner)
    tr = arg.reshape(1, m + 2, 1)
    if context == HOLD:
        return _term(hold_creep(tr, kappa, p), 1.0), None, None
    if context == MOVE_BASE and cp["start"].shape == (1,):  # piecewise constant: see move_base_tactile
        fac, dy = move_base_tactile(arg, cp, p)
        return _term(fac.reshape(tr.shape), 1.0), _term(dy.reshape(tr.shape), 0.0), _ZERO_TERM
    fac, dy, dx = context_tactile(context, tr, cp, p)
    return _term(fac, 1.0), _term(dy, 0.0), _term(dx, 0.0)


def _term(x: Arr, neutral: float) -> _Term:
    """A kernel output (``(1, m + 2, 6 or 1)`` or ``(1,)``) as rows ``(m + 2 or 1, 6 or 1)``, with
    whether its value before and after the segment is ``neutral`` for every pad."""
    rows = x[0] if x.ndim == 3 else x.reshape(1, -1)
    first, last = rows[0].tolist(), rows[-1].tolist()
    # list.count compares with == (fresh float objects: no identity shortcut applies)
    return rows, first.count(neutral) == len(first), last.count(neutral) == len(last)


def _ascending_state(tt: Arr, ep: Episode, p: SignalParams, out: list[Arr] | None = None) -> tuple[Arr, Arr, Arr] | None:
    """:func:`episode_pad_state` of ascending frame times ``tt`` ``(K,)`` inside the episode, as
    ``(K, 6)`` arrays of the same floats (written into ``out``'s three if given); None (use
    :func:`episode_pad_state`; nothing written) if a frame lies outside the episode or a
    contact centre is -0.0.

    At a frame time every segment but the one under way sits at a constant state (``tr`` 0
    before it, ``tr = dur`` after it). The frames are cut into pieces at each segment's first
    frame with ``t > start`` (``tr > 0``) and first frame with ``t > start + dur`` (from there
    on ``tr = dur``: ``t - start`` exceeds ``dur`` exactly, so its rounding is not below it);
    a segment's kernel is evaluated once, on its own frames and its two constants. A piece
    applies the segments in order, as :func:`episode_pad_state` does, with two exact
    shortcuts: a constant met before any per-frame array is applied to the pad vector (the
    same operations on the same operands), and a constant factor 1.0 or offset 0.0 is
    skipped (``x * 1.0 == x``; ``x + 0.0 == x`` unless ``x`` is -0.0, and a running sum that
    starts at a centre other than -0.0 never is -0.0: a sum is -0.0 only if both terms are).
    """
    c = ep.contact
    y0, x0 = c["y"][0], c["x"][0]
    n = tt.size
    if n == 0 or tt[0] < ep.start or tt[-1] >= ep.end:
        return None
    if any(v == 0.0 and math.copysign(1.0, v) < 0.0 for v in y0.tolist() + x0.tolist()):  # a centre -0.0
        return None
    segs = []
    cuts = {0, n}
    for seg in ep.segments:
        if seg[0] == IDLE:
            continue
        lo = int(tt.searchsorted(seg[1], side="right"))
        hi = max(lo, int(tt.searchsorted(math.nextafter(seg[1] + seg[2], math.inf), side="left")))
        segs.append((lo, hi, _segment_kernel(tt, lo, hi, seg, c["kappa"], p)))
        cuts.update((lo, hi))
    bounds = sorted(cuts)
    if out is None:
        out = [np.empty((n, N_PADS)) for _ in range(3)]
    starts = (c["A"][0], y0, x0)
    for a, b in zip(bounds[:-1], bounds[1:]):
        if b > a:
            for f in range(3):
                _piece(a, b, segs, f, starts[f], out[f][a:b])
    if ep.slips:
        t3 = tt[None, :, None]
        for t_s, sign, sp in ep.slips:
            fac, dy = slip_tactile(t3, t_s, sign, sp, p)
            out[0] *= fac[0]
            out[1] += dy[0]
    return out[0], out[1], out[2]


def _piece(a: int, b: int, segs: list, f: int, acc: Arr, dest: Arr) -> None:
    """Field ``f`` (0 amplitude: products, 1 and 2 centres: sums) over frames ``a..b-1``, which
    lie before, inside or after each segment as a whole, written into ``dest`` ``(b - a, 6)``;
    ``acc`` the field's start per pad."""
    op = np.multiply if f == 0 else np.add
    vector = True
    for lo, hi, kernel in segs:
        term = kernel[f]
        if term is None:
            continue
        rows, neutral_before, neutral_after = term
        if rows.shape[0] == 1:  # the same at every time
            if neutral_before:
                continue
            x = rows[0]
        elif b <= lo:
            if neutral_before:
                continue
            x = rows[0]
        elif a >= hi:
            if neutral_after:
                continue
            x = rows[-1]
        else:
            x = rows[a - lo + 1 : b - lo + 1]
        if not vector:
            op(acc, x, out=acc)
        elif x.ndim == 2:  # the first per-frame term: from here on in place, in ``dest``
            acc = op(acc, x, out=dest)
            vector = False
        else:
            acc = op(acc, x)
    if vector:
        dest[...] = acc


def render_pad_moments(
    amp: Arr,
    yc: Arr,
    xc: Arr,
    sy: Arr,
    sx: Arr,
    rows: int,
    normals: Callable[[int], Arr],
    p: SignalParams = DEFAULT_PARAMS,
    want_values: bool = False,
) -> tuple[Arr, Arr, Arr, tuple[Arr, Arr] | None]:
    """Render one pad for frames ``(n, K)`` and return its moments ``(S, Si, Sj)`` (each ``(n, K)``).

    Cells with noiseless value below the dead-band read 0; others read
    ``clip(rint(mu + sigma * eps), 0, 3500)``. ``normals(m)`` supplies the ``m`` standard
    normals for the cells above the dead-band, in C order over (frame, row, column).
    If the contact centre does not move within the call, only the cells that can
    exceed the dead-band are evaluated (the result is identical). With
    ``want_values`` also returns ``(flat cell index into (n, K, rows, 6), value)``.
    """
    n, k = amp.shape
    ii = np.arange(rows, dtype=float)
    jj = np.arange(PAD_COLS, dtype=float)
    cells = rows * PAD_COLS
    static = n == 1 and bool(np.all(yc == yc[:, :1])) and bool(np.all(xc == xc[:, :1]))
    if not static and p.deadband > 0.0:
        frame, ci, cj, mu_on = _moving_cells(amp, yc, xc, sy, sx, rows, p)
    else:
        if static:
            ey = np.exp(-((ii - yc[0, 0]) ** 2) / (2.0 * sy[0] ** 2))
            ex = np.exp(-((jj - xc[0, 0]) ** 2) / (2.0 * sx[0] ** 2))
            tmpl = (ey[:, None] * ex[None, :]).ravel()
            sup = np.flatnonzero(tmpl * amp.max() >= p.deadband)
            mu = amp[..., None] * tmpl[sup]  # (n, K, s)
            pos = np.flatnonzero(mu >= p.deadband)
            s = sup.size
            frame = pos // s if s else pos
            cell = sup[pos % s] if s else pos
        else:
            ey = np.exp(-((ii - yc[..., None]) ** 2) / (2.0 * sy[:, None, None] ** 2))
            ex = np.exp(-((jj - xc[..., None]) ** 2) / (2.0 * sx[:, None, None] ** 2))
            mu = amp[..., None, None] * (ey[..., :, None] * ex[..., None, :])
            pos = np.flatnonzero(mu >= p.deadband)
            frame = pos // cells
            cell = pos % cells
        mu_on = mu.reshape(-1)[pos]
        ci, cj = cell // PAD_COLS, cell % PAD_COLS
    vals = np.clip(np.rint(mu_on + p.noise_counts * normals(mu_on.size)), 0.0, FULL_SCALE)
    nk = n * k
    s_sum = np.bincount(frame, weights=vals, minlength=nk).reshape(n, k)
    s_i = np.bincount(frame, weights=vals * ci, minlength=nk).reshape(n, k)
    s_j = np.bincount(frame, weights=vals * cj, minlength=nk).reshape(n, k)
    extra = (frame * cells + ci * PAD_COLS + cj, vals) if want_values else None
    return s_sum, s_i, s_j, extra


def _moving_cells(amp: Arr, yc: Arr, xc: Arr, sy: Arr, sx: Arr, rows: int, p: SignalParams) -> tuple[Arr, Arr, Arr, Arr]:
    """The cells of :func:`render_pad_moments` that reach a positive dead-band, where the
    centre may move: ``(frame, row, column, mu)`` in C order over (frame, row, column),
    frames flat over ``(n, K)``. The same values as evaluating every cell of every frame
    (``mu = amp * (ey_i * ex_j)``, each factor from the same expression), on fewer cells:
    ``ey_i, ex_j <= 1`` and rounding is monotone, so ``mu <= amp * ey_i <= amp``, and a
    frame whose amplitude, or a row whose ``amp * ey_i``, lies below the dead-band
    has no cell that reaches it."""
    k = amp.shape[1]
    flat = amp.reshape(-1)
    live = np.flatnonzero(flat >= p.deadband)  # frames, ascending
    trial = live // k
    a = flat[live]
    ey = np.exp(-((_II[:rows] - yc.reshape(-1)[live][:, None]) ** 2) / (2.0 * sy ** 2)[trial][:, None])
    ex = np.exp(-((_JJ - xc.reshape(-1)[live][:, None]) ** 2) / (2.0 * sx ** 2)[trial][:, None])
    kept = np.flatnonzero(a[:, None] * ey >= p.deadband)  # (frame, row) pairs in C order
    lf = kept // rows
    row = kept - lf * rows
    mu = a.take(lf)[:, None] * (ey.take(kept)[:, None] * ex.take(lf, axis=0))
    on = np.flatnonzero(mu >= p.deadband)
    pair = on // PAD_COLS
    return live.take(lf.take(pair)), row.take(pair), on - pair * PAD_COLS, mu.take(on)


def render_rows(
    amp: Arr, yc: Arr, xc: Arr, pad: Arr, sy: Arr, sx: Arr, p: SignalParams = DEFAULT_PARAMS
) -> tuple[Arr, Arr, Arr]:
    """The cells above the dead-band of many pad frames (*rows*) at once, before noise.

    Row ``r`` is pad ``pad[r]`` with amplitude ``amp[r] > 0``, centre ``(yc[r], xc[r])``
    and spreads ``(sy[r], sx[r])``. Returns ``(count, cell, mu)``: ``count[r]`` cells of
    row ``r`` reach the dead-band; ``cell`` (flat index ``i * 6 + j``) and their
    noiseless values ``mu = amp * (ey_i * ex_j)`` follow row by row, cells ascending:
    the order in which :func:`render_pad_moments` draws its normals when the rows are
    laid out (pad, frame). The values are bit-identical to :func:`render_pad_moments`.
    """
    count, sel, mu, sup_cell, _first = _row_cells(amp, yc, xc, pad, sy, sx, p)
    return count, sup_cell[sel], mu


def _row_cells(
    amp: Arr, yc: Arr, xc: Arr, pad: Arr, sy: Arr, sx: Arr, p: SignalParams, scratch: _Scratch | None = None
) -> tuple[Arr, Arr, Arr, Arr, Arr]:
    """:func:`render_rows` with the cells left as indices: ``(count, sel, mu, sup_cell, first)``,
    the flat cell of kept cell ``m`` being ``sup_cell[sel[m]]``, row ``r``'s cells starting at
    ``first[r]``.

    Consecutive rows with the same pad and centre share one template ``ey_i * ex_j``
    (a hold, a move_base phase, a jerk of a slip), and only the template's cells that
    can reach the dead-band at the run's peak amplitude are evaluated per frame; when
    every one of them reaches it (nearly always) nothing is filtered. With ``scratch`` the
    per-cell ``sel`` and ``mu`` are written into its work arrays.
    """
    n = amp.size
    if n == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    change = np.empty(n, dtype=bool)
    change[0] = True
    np.not_equal(pad[1:], pad[:-1], out=change[1:])
    change[1:] |= (yc[1:] != yc[:-1]) | (xc[1:] != xc[:-1]) | (sy[1:] != sy[:-1]) | (sx[1:] != sx[:-1])
    starts = change.nonzero()[0]
    run = change.cumsum() - 1
    ey = np.exp(-((_II - yc[starts][:, None]) ** 2) / (2.0 * sy[starts][:, None] ** 2))
    ex = np.exp(-((_JJ - xc[starts][:, None]) ** 2) / (2.0 * sx[starts][:, None] ** 2))
    ey *= _ROW_OK[pad[starts]]  # rows a distal pad does not have read nothing
    tmpl = (ey[:, :, None] * ex[:, None, :]).reshape(-1)
    # a cell below the dead-band at the run's peak amplitude is below it in every frame
    peak = np.maximum.reduceat(amp, starts)
    sup_flat = (tmpl * peak.repeat(MAX_ROWS * PAD_COLS) >= p.deadband).nonzero()[0]
    sup_tmpl = tmpl[sup_flat]
    sup_run = sup_flat // (MAX_ROWS * PAD_COLS)
    sup_cell = sup_flat - sup_run * (MAX_ROWS * PAD_COLS)  # sup_flat % 84 (one integer division, not two)
    count = np.bincount(sup_run, minlength=starts.size)
    offset = count.cumsum() - count
    per_row = count[run]
    first = per_row.cumsum() - per_row
    total = int(first[-1] + per_row[-1])
    if scratch is None:
        idx = np.arange(total)
        idx -= np.repeat(first - offset[run], per_row)
        mu = np.repeat(amp, per_row)
        mu *= sup_tmpl[idx]
    else:
        idx = np.subtract(scratch.arange(total), (first - offset[run]).repeat(per_row), out=scratch.get("idx", total, np.int64))
        mu = np.take(sup_tmpl, idx, out=scratch.get("mu", total, float), mode="clip")
        mu *= amp.repeat(per_row)  # amp * w, as above (a product does not depend on the order)
    # every cell reaches the dead-band iff it does at its run's lowest amplitude (rounding is
    # monotonic: amp <= amp' gives amp * w <= amp' * w), checked on the templates, not the cells
    low = np.minimum.reduceat(amp, starts)
    if bool((sup_tmpl * low.repeat(count) >= p.deadband).all()):
        return per_row, idx, mu, sup_cell, first
    keep = np.flatnonzero(mu >= p.deadband)
    # kept cells per row: positions of the row starts among the kept cells
    at = np.searchsorted(keep, np.append(first, idx.size))
    return np.diff(at), idx[keep], mu[keep], sup_cell, at[:-1]


def frame_moments(frames: Arr) -> Arr:
    """Per-pad moments ``(..., 6, 3) = (sum P, sum i P, sum j P)`` of frames ``(..., 6, 14, 6)``."""
    f = np.asarray(frames, dtype=float)
    ii = np.arange(MAX_ROWS, dtype=float)
    jj = np.arange(PAD_COLS, dtype=float)
    s = f.sum(axis=(-1, -2))
    si = (f.sum(axis=-1) * ii).sum(axis=-1)
    sj = (f.sum(axis=-2) * jj).sum(axis=-1)
    return np.stack([s, si, sj], axis=-1)


# --------------------------------------------------------------------------- block rendering


@dataclass(frozen=True, slots=True)
class _Rows:
    """The pad frames (*rows*) with contact in a set of blocks, laid out (unit, pad, frame):
    ``frame`` indexes the blocks' concatenated frames; the rest are per-row pad states."""

    frame: Arr
    pad: Arr
    #: ``frame * 6 + pad``
    slot: Arr
    amp: Arr
    yc: Arr
    xc: Arr
    sy: Arr
    sx: Arr


def _episode_units(t: Arr, nb: int, episodes: Sequence[Episode], ep_starts: list[float]) -> list[tuple[int, int, int]]:
    """The (block, episode) frame ranges ``(lo, hi, episode number)`` of ``nb`` concatenated
    blocks of frame times ``t``, in draw order (``ep_starts``: the episodes' starts, ascending)."""
    B = TACTILE_BLOCK
    units: list[tuple[int, int, int]] = []
    for i in range(nb):
        tb = t[i * B : (i + 1) * B]
        t_first, t_last = float(tb[0]), float(tb[-1])
        first = bisect.bisect_right(ep_starts, t_first) - 1
        for ei in range(max(first, 0), len(episodes)):
            ep = episodes[ei]
            if ep.start > t_last:
                break
            lo = int(tb.searchsorted(ep.start, side="left"))
            hi = int(tb.searchsorted(ep.end, side="left"))
            if hi > lo:
                units.append((i * B + lo, i * B + hi, ei))
    return units


def _episode_state(t: Arr, ranges: list[tuple[int, int]], ep: Episode, p: SignalParams, state: Arr) -> Arr | slice:
    """The frames of an episode's ranges (a slice if they are one run), with the pads'
    amplitude, row and column centres there written into ``state[0..2, frames]`` (each
    ``(frames, 6)``): :func:`_ascending_state` where it applies (frame times ascending: any
    render of blocks in order; for one run straight into ``state``), else :func:`episode_pad_state`."""
    run = all(ranges[i][1] == ranges[i + 1][0] for i in range(len(ranges) - 1))
    if run:
        sel: Arr | slice = slice(ranges[0][0], ranges[-1][1])  # one run of frames (neighbouring blocks)
    else:
        sel = np.concatenate([np.arange(lo, hi) for lo, hi in ranges])
    tt = t[sel]
    fast = _ascending_state(tt, ep, p, [state[f, sel] for f in range(3)] if run else None) if bool((tt[1:] >= tt[:-1]).all()) else None
    if fast is None:
        a, y, x = episode_pad_state(tt[None, :], ep, p)
        fast = (a[0], y[0], x[0])
    elif run:
        return sel  # written in place
    state[0, sel], state[1, sel], state[2, sel] = fast
    return sel


def _contact_rows(t: Arr, units: list[tuple[int, int, int]], episodes: Sequence[Episode], p: SignalParams, scratch: _Scratch) -> _Rows:
    """Pad states at every frame of the units, expanded to rows and kept where the pad is touched."""
    nf = t.size
    # amplitude, row centre, column centre, row spread, column spread of (frame, pad); only
    # the units' frames are written, and only they are read
    state = scratch.get("state", 5 * nf * N_PADS, float).reshape(5, nf, N_PADS)
    by_ep: dict[int, list[tuple[int, int]]] = {}
    for lo, hi, ei in units:
        by_ep.setdefault(ei, []).append((lo, hi))
    pads = {}
    for ei, ranges in by_ep.items():
        c = episodes[ei].contact
        sel = _episode_state(t, ranges, episodes[ei], p, state)
        state[3, sel] = c["sy"][0]
        state[4, sel] = c["sx"][0]
        # a pad without contact (amplitude 0) has amplitude 0 (or NaN) in every frame: no rows
        pads[ei] = _PADS[c["A"][0] != 0][:, None]
    # rows laid out (unit, pad, frame), as flat indices frame * 6 + pad into a field
    idx = np.concatenate([(np.arange(lo * N_PADS, hi * N_PADS, N_PADS) + pads[ei]).reshape(-1) for lo, hi, ei in units])
    flat = state.reshape(5, -1)
    idx = idx[flat[0][idx] > 0]
    r = flat.take(idx, axis=1, mode="clip")  # idx in range: no bounds to check
    frame = idx // N_PADS
    pad = idx - frame * N_PADS  # idx % N_PADS (one integer division, not two)
    return _Rows(frame, pad, idx, r[0], r[1], r[2], r[3], r[4])


def _run_of_times(times: list[Arr], first: int, k0: int, k1: int, t0: float, t1: float) -> tuple[int, int]:
    """The frames ``lo .. hi - 1`` among ``k0 .. k1 - 1`` with ``t0 <= t < t1``, ``times`` being the
    frame times of neighbouring blocks from frame ``first`` on (ascending: the frames are one
    run, from the first with ``t >= t0`` to the first with ``t >= t1``)."""
    B = TACTILE_BLOCK
    lo = hi = None
    for i, tb in enumerate(times):
        base = first + i * B
        a = max(k0 - base, 0)
        tb = tb[a : min(k1 - base, B)]
        if not tb.size:
            continue
        last = tb[-1]
        if lo is None and last >= t0:
            lo = base + a + int(tb.searchsorted(t0, side="left"))
        if last >= t1:
            hi = base + a + int(tb.searchsorted(t1, side="left"))
            break
    hi = k1 if hi is None else hi
    return (hi if lo is None else min(lo, hi)), hi


def _cut_shares(arrays: list[Arr], shares: list[tuple[int, int, int]]) -> Arr:
    """The frames ``shares`` names (``(i, a, b)``: frames ``a .. b - 1`` of ``arrays[i]``, one
    array per neighbouring block), in order, as one new array."""
    if not shares:
        return arrays[0][:0].copy()
    if len(shares) == 1:
        i, a, b = shares[0]
        return arrays[i][a:b].copy()
    return np.concatenate([arrays[i][a:b] for i, a, b in shares])


def episode_blocks(episodes: Sequence[Episode], rate: float, clip: float) -> list[int]:
    """The tactile blocks holding frames of the ``episodes`` (frame ``k`` at ``k / rate`` give or
    take ``clip`` s), ascending."""
    out: set[int] = set()
    for ep in episodes:
        k0 = max(int(math.floor((ep.start - clip) * rate)), 0)
        k1 = max(int(math.ceil((ep.end + clip) * rate)), k0)
        out.update(range(k0 // TACTILE_BLOCK, k1 // TACTILE_BLOCK + 1))
    return sorted(out)


def holding_seconds(episodes: Sequence[Episode], until: float) -> float:
    """Seconds with an object in the hand before ``until`` (the episodes cut there)."""
    return float(sum(max(0.0, min(ep.end, until) - ep.start) for ep in episodes))


class _WorkerRender:
    """What a worker rendering a :class:`TactileArray` ahead does with a group of neighbouring
    blocks: renders their frame times and moments and, given ``flow`` (the tactile detector's
    ``flow_ahead``), their flow hint values, carried over from the group before it when that
    one ends just before (else the first two frames' are NaN)."""

    def __init__(self, array: "TactileArray", flow: Callable[[Arr, Arr | None], Arr] | None) -> None:
        self.array = array
        self.flow = flow
        self.last: tuple[int, Arr] | None = None  # the last block rendered and its last two frames

    def __call__(self, group: list[int]) -> list[tuple[Arr, ...]]:
        got = self.array.render_here(group, False)
        if self.flow is None:
            return [(t, mom) for t, mom, _fr in got]
        moms = [m for _t, m, _fr in got]
        if self.last is not None and self.last[0] == group[0] - 1:  # the two frames before, in one copy with the group's
            values = self.flow(np.concatenate([self.last[1]] + moms), None)[2:]
        else:
            values = self.flow(np.concatenate(moms), None)
        self.last = (group[-1], moms[-1][-2:].copy())
        B = TACTILE_BLOCK
        return [(t, m, values[i * B : (i + 1) * B]) for i, (t, m, _fr) in enumerate(got)]


class TactileArray:
    """Deterministic tactile frames of one mission (see the module docstring)."""

    def __init__(self, seed: int, episodes: Sequence[Episode], faults: Sequence[SensorFault], params: SignalParams) -> None:
        self.seed = seed
        self.episodes = tuple(episodes)
        self.faults = tuple(f for f in faults if f.sensor == "tactile")
        self.params = params
        self.rate = params.tactile_rate
        self.jitter = Jitter(seed, params)
        self._normals = BlockStream(seed, STREAM_TACTILE)
        self._ep_starts = [float(ep.start) for ep in self.episodes]
        self._cache: dict[tuple[int, bool], Rendered] = {}
        #: flow hint values of cached blocks that came from a worker rendering ahead (by block)
        self._flow: dict[int, Arr] = {}
        self._scratch = _Scratch()
        #: the worker rendering ahead, while one runs (:meth:`start_ahead`), and what it gave
        self.ahead = Ahead()
        #: frame times ascend (jitter under half a frame period): a span of times is a run of frames
        self._ordered = 2.0 * params.tactile_jitter_clip < 1.0 / params.tactile_rate

    def times(self, index: Arr) -> Arr:
        """Jittered time of each frame number."""
        k = np.asarray(index, dtype=np.int64)
        return k / self.rate + self.jitter(k)

    def _times_range(self, k0: int, k1: int) -> Arr:
        """:meth:`times` of the frames ``k0 .. k1 - 1`` (``k0 < k1``)."""
        return np.arange(k0, k1, dtype=np.int64) / self.rate + self.jitter.span(k0, k1)

    def _block(self, b: int, frames: bool) -> Rendered:
        hit = self._cache.get((b, frames))
        if hit is not None:
            return hit
        return self.render_blocks([b], frames)[0]

    def _noisy_values(self, rows: _Rows, count: Arr, mu: Arr, blocks: Arr) -> Arr:
        """Cell readings ``clip(rint(mu + noise), 0, FULL_SCALE)``; each block's normals from its own generator."""
        per_block = np.bincount(rows.frame >> _BLOCK_SHIFT, weights=count, minlength=blocks.size).astype(np.int64)
        vals = self._scratch.get("vals", mu.size, float)
        at = 0
        for i in range(blocks.size):
            c = int(per_block[i])
            if c:
                tactile_normals(self.seed, int(blocks[i]), c, out=vals[at : at + c], stream=self._normals)
                at += c
        vals *= self.params.noise_counts
        vals += mu
        np.rint(vals, out=vals)
        vals.clip(0.0, FULL_SCALE, out=vals)
        return vals

    # ------------------------------------------------------------------ rendering ahead
    def ahead_blocks(self) -> list[int]:
        """The blocks with frames of an object-in-hand episode, ascending: what a worker
        rendering ahead renders (:mod:`desmon.detectors.signals.ahead`)."""
        return episode_blocks(self.episodes, self.rate, self.params.tactile_jitter_clip)

    def start_ahead(self, flow: Callable[[Arr, Arr | None], Arr] | None = None) -> RenderAhead:
        """Fork a worker that renders this array's episode blocks ahead (stop it with
        :meth:`stop_ahead`); blocks of frames are then taken from it where it has them. With
        ``flow`` (``desmon.detectors.tactile.flow_ahead``) it works out their tactile flow too,
        which :meth:`between` then hands out (``TactileBlock.flow``)."""
        B = TACTILE_BLOCK
        shapes = [(B,), (B, N_PADS, 3)] + ([(B,)] if flow is not None else [])
        return self.ahead.start(_WorkerRender(self, flow), self.ahead_blocks(), shapes)

    def stop_ahead(self) -> None:
        """Stop the worker rendering ahead, if one runs; from then on every block is rendered here."""
        self.ahead.stop()

    @property
    def ahead_taken(self) -> int:
        """Blocks taken from workers rendering ahead, over this array's life."""
        return self.ahead.taken

    def render_blocks(self, blocks: Sequence[int], frames: bool) -> list[Rendered]:
        """:meth:`render_here`, with the blocks a worker rendering ahead has taken from it (the
        same bytes; full frames are always rendered here)."""
        ahead = self.ahead.worker
        if ahead is None or frames:
            return self.render_here(blocks, frames)
        got = [ahead.take(int(b)) for b in blocks]
        rest = [b for b, g in zip(blocks, got) if g is None]
        local = iter(self.render_here(rest, False)) if rest else iter(())
        out = []
        for b, g in zip(blocks, got):
            if g is None:
                out.append(next(local))
            else:
                res = (g[0], g[1], None)
                self._keep(int(b), False, res)
                if len(g) > 2:
                    self._flow[int(b)] = g[2]
                out.append(res)
        return out

    def _keep(self, block: int, frames: bool, res: Rendered) -> None:
        if len(self._cache) >= TACTILE_CACHE:
            oldest = next(iter(self._cache))
            del self._cache[oldest]
            if not oldest[1]:  # moments: their flow goes with them
                self._flow.pop(oldest[0], None)
        self._cache[(block, frames)] = res

    def render_here(self, blocks: Sequence[int], frames: bool) -> list[Rendered]:
        """Render whole tactile blocks (``TACTILE_BLOCK`` frames each) in one vectorised pass.

        Block ``b``'s frames depend only on the seed and ``b``: its normals come from
        the generator keyed ``(seed, tactile, b)``, drawn per object-in-hand episode in
        the block, pad by pad, frame by frame, cell by cell (as the per-pad reference
        :func:`render_pad_moments` does), so rendering blocks together or one by one
        gives the same bytes.
        """
        B = TACTILE_BLOCK
        nb = len(blocks)
        barr = np.asarray(blocks, dtype=np.int64)
        if nb and int(barr[-1]) - int(barr[0]) + 1 == nb and bool((barr[1:] > barr[:-1]).all()):  # neighbouring blocks
            t = self._times_range(int(barr[0]) * B, (int(barr[-1]) + 1) * B)
        else:
            t = self.times((barr[:, None] * B + np.arange(B, dtype=np.int64)[None, :]).reshape(-1))
        mom = np.zeros((t.size, N_PADS, 3))
        fr = np.zeros((t.size, N_PADS, MAX_ROWS, PAD_COLS), dtype=np.int16) if frames else None
        units = _episode_units(t, nb, self.episodes, self._ep_starts)
        if units:
            rows = _contact_rows(t, units, self.episodes, self.params, self._scratch)
            count, sel, mu, sup_cell, first = _row_cells(rows.amp, rows.yc, rows.xc, rows.pad, rows.sy, rows.sx, self.params, self._scratch)
            vals = self._noisy_values(rows, count, mu, barr)
            hit = count.nonzero()[0]
            if hit.size:
                at = rows.slot * 3  # (frame, pad, 0) in the flat moments
                if hit.size < count.size:
                    first, at = first[hit], at[hit]
                flat = mom.reshape(-1)
                flat[at] = np.add.reduceat(vals, first)
                code = np.take(_CELL_CODE[sup_cell], sel, out=mu, mode="clip")  # mu is read no more
                packed = np.add.reduceat(np.multiply(code, vals, out=code), first)
                sum_j = np.floor(packed / _PACK)  # exact: integers and a power of two
                # sum i P exactly, -0.0 where every value is -0.0 (as a sum of them would be)
                flat[at + 1] = np.copysign(packed - sum_j * _PACK, packed)
                flat[at + 2] = sum_j
            if fr is not None:
                cell = sup_cell[sel]
                rr = np.repeat(np.arange(count.size), count)
                fr[rows.frame[rr], rows.pad[rr], cell // PAD_COLS, cell % PAD_COLS] = vals.astype(np.int16)
        out = []
        for i in range(nb):
            res = (t[i * B : (i + 1) * B], mom[i * B : (i + 1) * B], fr[i * B : (i + 1) * B] if fr is not None else None)
            self._keep(int(barr[i]), frames, res)
            out.append(res)
        return out

    def clean(self, k: Arr, frames: bool) -> Rendered:
        """Fault-free frame times, moments and (if ``frames``) frames of frame numbers ``k``."""
        if k.size and int(k.min()) // TACTILE_BLOCK == int(k.max()) // TACTILE_BLOCK:
            b0 = int(k[0]) // TACTILE_BLOCK
            bt, bm, bf = self._block(b0, frames)
            j = k - b0 * TACTILE_BLOCK
            return bt[j], bm[j], (bf[j] if bf is not None else None)
        if k.size and (k.ndim == 1 and int(k[-1]) - int(k[0]) + 1 == k.size or int(k.max()) - int(k.min()) < 3 * TACTILE_BLOCK):
            return self._clean_span(k, frames)
        t = np.empty(k.shape)
        mom = np.empty(k.shape + (N_PADS, 3))
        fr = np.empty(k.shape + (N_PADS, MAX_ROWS, PAD_COLS), dtype=np.int16) if frames else None
        blocks = k // TACTILE_BLOCK
        uniq = [int(b) for b in np.unique(blocks)]
        missing = [b for b in uniq if (b, frames) not in self._cache]
        rendered = dict(zip(missing, self.render_blocks(missing, frames))) if missing else {}
        for b in uniq:
            sel = blocks == b
            bt, bm, bf = rendered[b] if b in rendered else self._block(b, frames)
            j = k[sel] - b * TACTILE_BLOCK
            t[sel] = bt[j]
            mom[sel] = bm[j]
            if fr is not None and bf is not None:
                fr[sel] = bf[j]
        return t, mom, fr

    def _clean_span(self, k: Arr, frames: bool) -> Rendered:
        """:meth:`clean` of frame numbers within a few neighbouring blocks, or of consecutive
        ones (a request by time): every block of the span, rendered if missing; their slices
        are copied (consecutive frames) or concatenated into one table that ``k`` indexes."""
        B = TACTILE_BLOCK
        b0, b1 = int(k.min()) // B, int(k.max()) // B
        span = range(b0, b1 + 1)
        missing = [b for b in span if (b, frames) not in self._cache]
        rendered = dict(zip(missing, self.render_blocks(missing, frames))) if missing else {}
        parts = [rendered[b] if b in rendered else self._block(b, frames) for b in span]
        j = k - b0 * B
        lo, hi = int(j[0]), int(j[-1]) + 1
        if k.ndim == 1 and hi - lo == j.size and bool((j[1:] - j[:-1] == 1).all()):
            # consecutive frames (a request by time): the blocks' slices, copied once
            cuts = [(i, slice(max(lo - i * B, 0), min(hi - i * B, B))) for i in range(len(parts)) if lo < (i + 1) * B and hi > i * B]
            fields = range(3) if frames else range(2)
            out = [np.concatenate([parts[i][f][c] for i, c in cuts]) for f in fields]  # type: ignore[index]
            return out[0], out[1], (out[2] if frames else None)
        t = np.concatenate([part[0] for part in parts])[j]
        mom = np.concatenate([part[1] for part in parts])[j]
        fr = np.concatenate([part[2] for part in parts])[j] if frames else None  # type: ignore[misc]
        return t, mom, fr

    def at(self, index: Arr, frames: bool = False) -> TactileBlock:
        """Frames by frame number (int array, >= 0), faults applied."""
        k = np.asarray(index, dtype=np.int64)
        t, mom, fr = self.clean(k, frames)  # fresh arrays
        if not self.faults and k.ndim == 1:
            return TactileBlock(k.copy() if k is index else k, t, mom, fr)
        keep = np.ones(k.shape, dtype=bool)
        for f in self.faults:
            hit = (t >= f.start) & (t < f.end)
            if not hit.any():
                continue
            if f.mode == "silent":
                keep &= ~hit
            elif f.mode == "zero":
                mom[hit] = 0.0
                if fr is not None:
                    fr[hit] = 0
            else:
                self._stick(f, hit, mom, fr, frames)
        return TactileBlock(k[keep], t[keep], mom[keep], fr[keep] if fr is not None else None)

    def _stick(self, f: SensorFault, hit: Arr, mom: Arr, fr: Arr | None, frames: bool) -> None:
        """A stuck fault: the ``hit`` frames repeat the last good frame before ``f.start`` (if any)."""
        cand = tactile_nominal_indices(f.start - 0.2, f.start, self.rate, self.params.tactile_jitter_clip)
        before = cand[self.times(cand) < f.start]
        if before.size:
            _, lm, lf = self.clean(before[-1:], frames)
            mom[hit] = lm[0]
            if fr is not None and lf is not None:
                fr[hit] = lf[0]

    def _prefetch(self, k0: int, k1: int, t1: float, frames: bool) -> None:
        """Render the blocks of frames ``k0..k1`` if any is missing, together with the blocks
        up to the end of the object-in-hand episode at ``t1`` (at most ``PREFETCH_S``
        ahead): a consumer reading a mission in chunks then pays one vectorised render
        per episode instead of one per chunk. Only *when* a block is rendered changes."""
        B = TACTILE_BLOCK
        b0, b1 = k0 // B, k1 // B
        if all((b, frames) in self._cache for b in range(b0, b1 + 1)):
            return
        b2 = b1
        ei = bisect.bisect_right(self._ep_starts, t1) - 1
        if ei >= 0 and self.episodes[ei].end > t1:
            end = min(self.episodes[ei].end, t1 + PREFETCH_S)
            b2 = max(b1, int(math.ceil((end + self.params.tactile_jitter_clip) * self.rate)) // B)
        if b2 - b0 + 1 > TACTILE_CACHE:
            b2 = b1
            if b2 - b0 + 1 > TACTILE_CACHE:
                return  # a long request: clean() renders it without the cache
        missing = [b for b in range(b0, b2 + 1) if (b, frames) not in self._cache]
        self.render_blocks(missing, frames)

    def _cached_between(self, k0: int, k1: int, t0: float, t1: float, frames: bool) -> TactileBlock | None:
        """:meth:`between` of candidate frames ``k0 .. k1 - 1`` read from the cached blocks
        (None if one is missing), without faults: frame times ascend, so the frames with
        ``t0 <= t < t1`` are one run, cut from the blocks' own times, moments and frames (and
        their flow, where a worker gave it for every one of the blocks)."""
        B = TACTILE_BLOCK
        cache = self._cache
        b0 = k0 >> _BLOCK_SHIFT
        hits = []
        for b in range(b0, ((k1 - 1) >> _BLOCK_SHIFT) + 1):
            hit = cache.get((b, frames))
            if hit is None:
                return None
            hits.append(hit)
        lo, hi = _run_of_times([hit[0] for hit in hits], b0 * B, k0, k1, t0, t1)
        # each block's share of frames lo .. hi - 1, as (block, first, one past the last)
        shares = [(i, max(lo - base, 0), min(hi - base, B)) for i, base in enumerate(range(b0 * B, (b0 + len(hits)) * B, B)) if lo < base + B and hi > base]
        fields = [_cut_shares([hit[f] for hit in hits], shares) for f in range(3 if frames else 2)]  # type: ignore[misc]
        flow = None
        if not frames:
            flows = [self._flow.get(b0 + i) for i in range(len(hits))]
            if not any(v is None for v in flows):
                flow = _cut_shares(flows, shares)  # type: ignore[arg-type]
        return TactileBlock(np.arange(lo, hi, dtype=np.int64), fields[0], fields[1], fields[2] if frames else None, flow)

    def between(self, t0: float, t1: float, frames: bool = False) -> TactileBlock:
        """All frames with ``t0 <= t < t1`` (moments always; full frames if ``frames``)."""
        k0, k1 = tactile_nominal_range(t0, t1, self.rate, self.params.tactile_jitter_clip)
        if k1 > k0:
            self._prefetch(k0, k1 - 1, t1, frames)
            if self._ordered and not self.faults:
                hit = self._cached_between(k0, k1, t0, t1, frames)
                if hit is not None:
                    return hit
        cand = np.arange(k0, k1, dtype=np.int64)
        t = self._times_range(k0, k1) if k1 > k0 else self.times(cand)  # cand: consecutive
        return self.at(cand[(t >= t0) & (t < t1)], frames=frames)
