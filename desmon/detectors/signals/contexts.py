"""Action contexts as a signal source: what grasping, releasing, rotating and driving the base
do to the wrench (bumps, inertia, base vibration) and to the tactile pads (pressure ramps,
contact drift, rotation arcs), research note §3.1–3.2 and §4.

One function per context draws its random parameters (:func:`draw_context`); two kernels
turn them into the wrench disturbance (:func:`context_force`) and the tactile pressure
factor and centre offsets (:func:`context_tactile`). Hold adds a slow pressure creep
(:func:`hold_creep`); idle adds nothing.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from desmon.detectors.signals.common import DEFAULT_PARAMS, N_PADS, Arr, Params, SignalParams, half_sine, jerky, no_signal_model
from desmon.detectors.signals.common import uniform as _u
from desmon.errors import SignalError
from desmon.model.actions import GRASP, HOLD, IDLE, MOVE_BASE, RELEASE, ROTATE_CCW, ROTATE_CW


def _select(shape: tuple[int, ...], conds: tuple[Arr, ...], choices: tuple[Arr, ...]) -> Arr:
    """``np.select(conds, choices, 0.0)`` of float ``choices`` broadcast to ``shape`` (the
    same values: the first condition that holds wins), without its argument checks."""
    out = np.zeros(shape)
    for cond, choice in zip(conds[::-1], choices[::-1]):
        np.copyto(out, choice, where=cond)
    return out


def base_profile(tau: Arr, a_max: Arr, leg: float, pause: float, *, speed: bool = True) -> tuple[Arr, Arr | None]:
    """Base acceleration and speed for the back-and-forth drive: pulses +,-, pause, -,+.

    ``tau`` is time since the drive started; each pulse lasts ``sqrt(leg / a_max)``.
    With ``speed`` False the speed is not computed (None).
    """
    ta = np.sqrt(leg / a_max)
    t2 = tau - 2.0 * ta - pause
    c1 = (tau >= 0) & (tau < ta)
    c2 = (tau >= ta) & (tau < 2 * ta)
    c3 = (t2 >= 0) & (t2 < ta)
    c4 = (t2 >= ta) & (t2 < 2 * ta)
    shape = np.broadcast_shapes(tau.shape, np.shape(a_max))
    conds = (c1, c2, c3, c4)
    acc = _select(shape, conds, (a_max, -a_max, -a_max, a_max))
    if not speed:
        return acc, None
    vel = _select(shape, conds, (a_max * tau, a_max * (2 * ta - tau), -a_max * t2, -a_max * (2 * ta - t2)))
    return acc, vel


def base_duration(a_max: float, p: SignalParams = DEFAULT_PARAMS) -> float:
    """Length of the drive (from its start) for a given peak acceleration."""
    return 4.0 * math.sqrt(p.base_leg / a_max) + p.base_pause


# --------------------------------------------------------------------------- parameter draws


def _draw_grasp(rng: np.random.Generator, n: int, contact: Arr | None, p: SignalParams) -> Params:
    t_on = _u(rng, p.grasp_on, (n, N_PADS))
    ramp = _u(rng, p.grasp_ramp, (n, N_PADS))
    done = t_on + ramp
    if contact is not None:
        done = np.where(contact, done, 0.0)
    return {
        "t_on": t_on,
        "ramp": ramp,
        "dy": rng.normal(0.0, p.grasp_drift, (n, N_PADS)),
        "dx": rng.normal(0.0, p.grasp_drift, (n, N_PADS)),
        "amp": rng.normal(0.0, p.grasp_amp, n),
        "b0": done.max(axis=1) + _u(rng, p.grasp_delay, n),
        "bw": _u(rng, p.grasp_bump, n),
    }


def _draw_release(rng: np.random.Generator, n: int, contact: Arr | None, p: SignalParams) -> Params:
    return {
        "t_off": _u(rng, p.release_off, (n, N_PADS)),
        "ramp": _u(rng, p.release_ramp, (n, N_PADS)),
        "dy": rng.normal(0.0, p.release_drift, (n, N_PADS)),
        "dx": rng.normal(0.0, p.release_drift, (n, N_PADS)),
        "amp": rng.normal(0.0, p.release_amp, n),
        "b0": _u(rng, p.release_start, n),
        "bw": _u(rng, p.release_bump, n),
    }


def _draw_rotate(ccw: bool) -> Callable[[np.random.Generator, int, Arr | None, SignalParams], Params]:
    def draw(rng: np.random.Generator, n: int, contact: Arr | None, p: SignalParams) -> Params:
        return {
            "t0": _u(rng, p.rot_start, n),
            "dur": _u(rng, p.rot_dur, n),
            "jerks": rng.integers(2, 5, n).astype(float),
            "arc": _u(rng, p.rot_arc_ccw if ccw else p.rot_arc_cw, n),
            "ydir": rng.normal(0.0, 0.5, n),
            "xdir": np.full(n, 1.0 if ccw else -1.0),
            "amp": rng.normal(0.0, p.rot_amp_ccw if ccw else p.rot_amp_cw, n),
        }

    return draw


def _draw_move_base(rng: np.random.Generator, n: int, contact: Arr | None, p: SignalParams) -> Params:
    a_max = _u(rng, p.base_amax, n)
    start = _u(rng, p.base_start, n)
    motion = 4.0 * np.sqrt(p.base_leg / a_max) + p.base_pause
    return {
        "start": start,
        "a_max": a_max,
        "gain": _u(rng, p.base_gain, n),
        "fv": _u(rng, p.base_fv, n),
        "phase": rng.uniform(0.0, 2 * math.pi, n),
        "settle": (rng.random(n) < p.base_settle_p).astype(float),
        "settle_t": start + rng.random(n) * motion,
        "settle_jump": _u(rng, p.base_settle_jump, n) * rng.choice([-1.0, 1.0], n),
    }


def _draw_nothing(rng: np.random.Generator, n: int, contact: Arr | None, p: SignalParams) -> Params:
    return {}


#: Parameter draw per context; each draws from ``rng`` in a fixed order (part of the seed contract).
_DRAWS: dict[str, Callable[[np.random.Generator, int, Arr | None, SignalParams], Params]] = {
    GRASP: _draw_grasp,
    RELEASE: _draw_release,
    ROTATE_CCW: _draw_rotate(True),
    ROTATE_CW: _draw_rotate(False),
    MOVE_BASE: _draw_move_base,
    HOLD: _draw_nothing,
    IDLE: _draw_nothing,
}


def draw_context(
    context: str, rng: np.random.Generator, n: int, contact: Arr | None, p: SignalParams = DEFAULT_PARAMS
) -> Params:
    """Random parameters of one action context for ``n`` trials (research note §3.1–3.2, §4).

    ``contact`` (``(n, 6)`` bool, pads touched) lets the grasp bump follow the last pad's contact.
    """
    draw = _DRAWS.get(context)
    if draw is None:
        raise SignalError(no_signal_model(context))
    return draw(rng, n, contact, p)


# --------------------------------------------------------------------------- kernels


def context_force(context: str, t_rel: Arr, cp: Params, p: SignalParams, coupling: float) -> Arr:
    """Context disturbance ``d_ctx`` along the slip axis (N) at ``t_rel`` seconds into the action.

    ``cp`` arrays have shape ``(n,)``; ``t_rel`` ``(n, K)``. Zero for hold / idle. The base
    drive adds its inertia (scaled by the sensor's ``coupling``) and a speed-proportional vibration.
    """
    col = {k: (v[:, None] if v.ndim == 1 else v) for k, v in cp.items()}
    if context == GRASP or context == RELEASE:
        return col["amp"] * half_sine(t_rel, col["b0"], col["bw"])
    if context in (ROTATE_CCW, ROTATE_CW):
        return col["amp"] * half_sine(t_rel, col["t0"], col["dur"])
    if context == MOVE_BASE:
        acc, vel = base_profile(t_rel - col["start"], col["a_max"], p.base_leg, p.base_pause)
        vib = p.base_kv * np.abs(vel) * np.sin(2 * math.pi * col["fv"] * t_rel + col["phase"])
        return coupling * col["gain"] * acc + vib
    return np.zeros(np.broadcast_shapes(t_rel.shape, (t_rel.shape[0], 1)))


def context_tactile(context: str, t_rel: Arr, cp: Params, p: SignalParams) -> tuple[Arr, Arr, Arr]:
    """Pressure factor and centre offsets (rows, columns) per pad, shapes broadcastable to ``(n, K, 6)``.

    ``t_rel`` ``(n, K, 1)`` is clipped by the caller to ``[0, duration]`` so that the
    state at the end of an action persists afterwards.
    """
    if context == GRASP or context == RELEASE:
        on = "t_on" if context == GRASP else "t_off"
        g = ((t_rel - cp[on][:, None, :]) / cp["ramp"][:, None, :]).clip(0.0, 1.0)
        if context == RELEASE:
            g = 1.0 - g
        rest = 1 - g
        return g, cp["dy"][:, None, :] * rest, cp["dx"][:, None, :] * rest
    if context in (ROTATE_CCW, ROTATE_CW):
        q = jerky(t_rel, cp["t0"][:, None, None], cp["dur"][:, None, None], cp["jerks"][:, None, None])
        arc = cp["arc"][:, None, None] * q
        return np.ones(1), arc * cp["ydir"][:, None, None], arc * cp["xdir"][:, None, None]
    if context == MOVE_BASE:
        acc, _ = base_profile(t_rel - cp["start"][:, None, None], cp["a_max"][:, None, None], p.base_leg, p.base_pause, speed=False)
        rel = acc / cp["a_max"][:, None, None]
        jump = cp["settle"][:, None, None] * cp["settle_jump"][:, None, None] * (t_rel >= cp["settle_t"][:, None, None])
        return 1.0 + 0.03 * rel, 0.05 * rel + jump, np.zeros(1)
    return np.ones(1), np.zeros(1), np.zeros(1)


def _drive_runs(t_rel: Arr, cp: Params, p: SignalParams) -> tuple[float, float, Arr, Arr, list[int], list[int]]:
    """One ``MOVE_BASE`` drive at non-decreasing times ``t_rel`` ``(K,)``: its peak acceleration
    ``a``, pulse length ``ta``, ``tau = t_rel - start``, ``t2 = tau - 2 ta - pause`` (the second
    half's time), and where ``tau`` and ``t2`` reach 0, ``ta`` and ``2 ta`` (by bisection): the
    pulses of :func:`base_profile` are ``tau`` in ``[0, ta)``, ``[ta, 2 ta)`` and ``t2`` in the same two."""
    a = float(cp["a_max"][0])
    ta = math.sqrt(p.base_leg / a)
    tau = t_rel - float(cp["start"][0])
    t2 = tau - 2.0 * ta
    t2 -= p.base_pause
    edges = (0.0, ta, 2 * ta)
    return a, ta, tau, t2, tau.searchsorted(edges).tolist(), t2.searchsorted(edges).tolist()


def move_base_tactile(t_rel: Arr, cp: Params, p: SignalParams) -> tuple[Arr, Arr]:
    """:func:`context_tactile`'s pressure factor and row offset of one ``MOVE_BASE`` trial
    (``cp`` arrays ``(1,)``) at non-decreasing times ``t_rel`` ``(K,)``, each ``(K,)`` (the
    column offset is zero): the same floats, from the same scalar operations.

    Both are piecewise constant: :func:`base_profile`'s four pulse conditions and the
    settle jump's ``t_rel >= settle_t`` each hold on one run of frames (``tau = t_rel -
    start`` and ``t2`` are non-decreasing: a rounded difference with a constant is
    monotonic), found by bisection; each frame gets the value of its (pulse, jump) case,
    the first pulse that holds winning as in :func:`base_profile`.
    """
    a, ta, tau, t2, (i0, i1, i2), (j0, j1, j2) = _drive_runs(t_rel, cp, p)
    case = np.zeros(t_rel.size, dtype=np.intp)
    case[j1:j2] = 4  # the later pulses first: an earlier one that holds overwrites them
    case[j0:j1] = 3
    case[i1:i2] = 2
    case[i0:i1] = 1
    case[int(t_rel.searchsorted(float(cp["settle_t"][0]))) :] += 5
    rel = [acc / a for acc in (0.0, a, -a, -a, a)]
    sj = float(cp["settle"][0]) * float(cp["settle_jump"][0])
    fac = np.array([1.0 + 0.03 * r for r in rel] * 2)
    dy = np.array([0.05 * r + sj * on for on in (0.0, 1.0) for r in rel])
    return fac.take(case), dy.take(case)


def trial_force(context: str, t_rel: Arr, cp: Params, p: SignalParams, coupling: float) -> Arr:
    """:func:`context_force` of one trial (``cp`` arrays of one row: ``(1,)``, or ``(1, 6)``
    for the per-pad ones) at non-decreasing times ``t_rel`` ``(K,)``, as ``(K,)``: the same
    floats from the same operations on each sample, the parameters taken as numbers (no
    broadcasting of one-element arrays). A ``MOVE_BASE`` drive: :func:`move_base_force`."""
    first = next(iter(cp.values()), None)  # every parameter of a draw has its trials on the first axis
    if first is not None and first.shape[:1] != (1,):
        raise SignalError(f"trial_force: parameters of shape {first.shape} hold {first.shape[0] if first.ndim else 0} trials; pass one trial's (first axis 1) or use context_force")
    if context == GRASP or context == RELEASE:
        return float(cp["amp"][0]) * _half_sine_ascending(t_rel, float(cp["b0"][0]), float(cp["bw"][0]))
    if context in (ROTATE_CCW, ROTATE_CW):
        return float(cp["amp"][0]) * _half_sine_ascending(t_rel, float(cp["t0"][0]), float(cp["dur"][0]))
    if context == MOVE_BASE:
        return move_base_force(t_rel, cp, p, coupling)
    return context_force(context, t_rel[None, :], cp, p, coupling)[0]


def _half_sine_ascending(t: Arr, t0: float, width: float) -> Arr:
    """:func:`half_sine` of non-decreasing times ``t`` ``(K,)``: the samples on ``[t0, t0 + width]``
    are one run (``u = (t - t0) / width`` is non-decreasing for ``width > 0``), where the sine is
    taken (clipping ``u`` there changes nothing); zero elsewhere."""
    if not width > 0.0:
        return half_sine(t, t0, width)
    u = t - t0
    u /= width
    a, b = u.searchsorted((0.0, 1.0), side="left").tolist()
    b += int(u[b:].searchsorted(1.0, side="right"))  # the samples at u == 1 exactly are inside too
    out = np.zeros(t.size)
    part = u[a:b]
    part *= np.pi
    np.sin(part, out=out[a:b])
    return out


def move_base_force(t_rel: Arr, cp: Params, p: SignalParams, coupling: float) -> Arr:
    """:func:`context_force` of one ``MOVE_BASE`` trial (``cp`` arrays ``(1,)``) at
    non-decreasing times ``t_rel`` ``(K,)``, as ``(K,)``: the same floats, from the same
    operations on each sample.

    The drive's four pulses (:func:`base_profile`) each hold on one run of samples (``tau =
    t_rel - start`` and ``t2`` are non-decreasing: a rounded difference with a constant is
    monotonic), found by bisection; the acceleration is set per run and the speed is worked
    out on the pulses only (zero elsewhere, as the selection leaves it). The vibration's sine
    is taken at every sample, so a zero speed gives the zero of the same sign."""
    if not (float(cp["a_max"][0]) > 0.0 and p.base_leg >= 0.0):  # outside the drive's domain (math.sqrt would raise): the general kernel
        return context_force(MOVE_BASE, t_rel[None, :], cp, p, coupling)[0]
    a, ta, tau, t2, (i0, i1, i2), (j0, j1, j2) = _drive_runs(t_rel, cp, p)
    acc = np.zeros(t_rel.size)
    vel = np.zeros(t_rel.size)
    # the later pulses first: an earlier one that holds overwrites them (the first that holds wins)
    acc[j1:j2] = a
    vel[j1:j2] = -a * (2 * ta - t2[j1:j2])
    acc[j0:j1] = -a
    vel[j0:j1] = -a * t2[j0:j1]
    acc[i1:i2] = -a
    vel[i1:i2] = a * (2 * ta - tau[i1:i2])
    acc[i0:i1] = a
    vel[i0:i1] = a * tau[i0:i1]
    vib = p.base_kv * np.abs(vel) * np.sin(2 * math.pi * float(cp["fv"][0]) * t_rel + float(cp["phase"][0]))
    return coupling * float(cp["gain"][0]) * acc + vib


def hold_creep(t_rel: Arr, kappa: Arr, p: SignalParams) -> Arr:
    """Slow pressure creep while holding, saturating at ``1 + kappa * tau``."""
    return 1.0 + kappa[:, None, None] * p.creep_tau * (1.0 - np.exp(-t_rel / p.creep_tau))
