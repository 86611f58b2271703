"""Batches for evaluation: ``n`` independent trials of one short timeline rendered at once with
the same kernels as a mission (:func:`simulate_batch`, used by :mod:`desmon.detectors.evaluation`).

Unlike a mission, a batch draws everything (parameters, noise, jitter) from one caller
generator, in a fixed order: contacts, segment parameters, slip constants, slip onsets,
wrench noise, frame jitter, cell noise pad by pad.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from desmon.detectors.signals.common import (
    DEFAULT_PARAMS,
    DOWN,
    GRAVITATIONAL,
    N_PADS,
    PAD_ROWS,
    PULLED,
    UP,
    Arr,
    Params,
    Segment,
    SignalParams,
    check_contexts,
    wrench_indices,
)
from desmon.detectors.signals.contexts import context_force, draw_context
from desmon.detectors.signals.episodes import Episode, draw_contact
from desmon.detectors.signals.slips import draw_slip, slip_force, slip_load_onset
from desmon.detectors.signals.tactile_array import episode_pad_state, render_pad_moments
from desmon.model.actions import HOLD, IDLE


@dataclass(frozen=True, slots=True)
class Batch:
    """``n`` independent trials on one common timeline (for vectorised evaluation).

    ``wrench_times (Kf,)``, ``wrench (n, Kf)``, ``tactile_times (n, Kt)``,
    ``moments (n, Kt, 6, 3)``; slip ground truth per trial (NaN where no slip).
    """

    wrench_times: Arr
    wrench: Arr
    tactile_times: Arr
    moments: Arr
    slip_onset: Arr
    load_onset: Arr
    force_sign: Arr


def _batch_wrench(
    timeline: Sequence[Segment], seg_params: Sequence[Params], rng: np.random.Generator, n: int,
    slip: tuple[Arr, Arr, Arr, Params], p: SignalParams, wrench_rate: float,
) -> tuple[Arr, Arr]:
    """Wrench grid times ``(Kf,)`` and samples ``(n, Kf)``: noise, context disturbances, slip loads."""
    kf = wrench_indices(0.0, timeline[-1].end, wrench_rate)
    tf = kf / wrench_rate
    t2 = np.broadcast_to(tf, (n, tf.size))
    sigma = p.force_noise_lwr if wrench_rate <= 50.0 else p.force_noise_ft
    coupling = 1.0 if wrench_rate <= 50.0 else p.ft_coupling_scale
    w = sigma * rng.standard_normal((n, tf.size))
    for s, cp in zip(timeline, seg_params):
        if s.context in (HOLD, IDLE):
            continue
        inside = (t2 >= s.start) & (t2 < s.end)
        w += np.where(inside, context_force(s.context, t2 - s.start, cp, p, coupling), 0.0)
    t_s_safe, sign, grav, sp = slip
    w += slip_force(t2, t_s_safe, sign, grav, sp)
    return tf, w


def _batch_tactile(
    timeline: Sequence[Segment], seg_params: Sequence[Params], contact: Params, rng: np.random.Generator, n: int,
    slip: tuple[Arr, Arr, Arr, Params], p: SignalParams,
) -> tuple[Arr, Arr]:
    """Jittered frame times ``(n, Kt)`` and moments ``(n, Kt, 6, 3)`` of the timeline's one episode."""
    end = timeline[-1].end
    kt = np.arange(0, int(math.ceil(end * p.tactile_rate)) + 1)
    jit = np.clip(rng.normal(0.0, p.tactile_jitter, (n, kt.size)), -p.tactile_jitter_clip, p.tactile_jitter_clip)
    tt = kt[None, :] / p.tactile_rate + jit
    tt = np.where(tt < 0, 0.0, tt)
    ep_start = next(s.start for s in timeline if s.context != IDLE)
    t_s_safe, sign, _, sp = slip
    ep = Episode(
        ep_start,
        end,
        contact,
        tuple((s.context, s.start, s.duration, cp) for s, cp in zip(timeline, seg_params) if s.context != IDLE),
        ((t_s_safe, sign, sp),),
    )
    amp, yc, xc = episode_pad_state(tt, ep, p)
    mom = np.zeros(tt.shape + (N_PADS, 3))
    for pad in range(N_PADS):
        s_, si, sj, _ = render_pad_moments(
            amp[..., pad], yc[..., pad], xc[..., pad], contact["sy"][:, pad], contact["sx"][:, pad],
            PAD_ROWS[pad], rng.standard_normal, p,
        )
        mom[..., pad, 0] = s_
        mom[..., pad, 1] = si
        mom[..., pad, 2] = sj
    return tt, mom


def simulate_batch(
    timeline: Sequence[Segment],
    n: int,
    rng: np.random.Generator,
    *,
    slip_window: tuple[float, float] | None = None,
    slip_direction: str = DOWN,
    slip_kind: str = PULLED,
    slip_fraction: float = 1.0,
    params: SignalParams = DEFAULT_PARAMS,
    wrench_rate: float = 50.0,
    first_trial: int = 0,
) -> Batch:
    """Render ``n`` trials of one timeline with the same kernels as a mission.

    The timeline must hold a single object-in-hand episode (optionally preceded by
    idle). With ``slip_window`` a slip with motion onset uniform in the window is
    overlaid on a fraction ``slip_fraction`` of the trials. Grasp types alternate by
    trial number (``first_trial`` keeps the alternation across chunks).
    """
    check_contexts(timeline)
    p = params
    two = (np.arange(first_trial, first_trial + n) % 2) == 1
    contact = draw_contact(rng, n, two, p)
    seg_params = [draw_context(s.context, rng, n, contact["contact"], p) for s in timeline]
    has_slip = np.zeros(n, dtype=bool)
    t_s = np.full(n, np.nan)
    sp = draw_slip(rng, n, p)
    if slip_window is not None:
        has_slip = rng.random(n) < slip_fraction
        t_s = np.where(has_slip, rng.uniform(slip_window[0], slip_window[1], n), np.nan)
    sign = np.full(n, 1.0 if slip_direction == UP else -1.0)
    grav = np.full(n, slip_kind == GRAVITATIONAL)
    slip = (np.where(has_slip, t_s, 1e9), sign, grav, sp)
    tf, w = _batch_wrench(timeline, seg_params, rng, n, slip, p, wrench_rate)
    tt, mom = _batch_tactile(timeline, seg_params, contact, rng, n, slip, p)
    load = np.where(has_slip, slip_load_onset(t_s, sp, grav), np.nan)
    fsign = np.where(has_slip, sign * np.where(grav, -1.0, 1.0), 0.0)
    return Batch(tf, w, tt, mom, t_s, load, fsign)
