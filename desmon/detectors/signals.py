"""Physics-like signal models for in-hand slip detection (wrench along the slip axis, six tactile pads).

The models follow ``research/slip-signals.md`` §3 with the §4 defaults (see
:class:`SignalParams`). Everything is vectorised: the *kernels* below take parameter
arrays with a leading trial axis ``n`` and time arrays ``(n, K)``, so the same code
renders one mission (``n = 1``, :class:`MissionSignals`) or thousands of calibration
trials at once (:func:`simulate_batch`, used by :mod:`desmon.detectors.evaluation`).

Conventions
-----------
* Time is in seconds from mission start (``t >= 0``).
* The wrench signal is the scalar force along the slip axis, in newtons, **positive
  = up**. A pulled slip *down* drives it negative; a gravitational slip down drives
  it positive (the wrist is unloaded), see :func:`slip_force`.
* Tactile pads are ordered ``PAD_NAMES`` (thumb_prox, thumb_dist, f1_prox, f1_dist,
  f2_prox, f2_dist). Proximal pads have 14 rows, distal pads 13 rows, all 6 columns.
  A frame array has shape ``(..., 6, 14, 6)`` (pad, row along the finger, column
  across it); distal pads leave row 13 at zero. Values are raw counts (int16,
  0..3500). Detectors do not need whole frames: they consume per-pad *moments*
  ``(..., 6, 3) = (sum P, sum i*P, sum j*P)`` (float64, exact integer values), from
  which the centre of pressure follows; :func:`frame_moments` converts frames.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Callable, Final, Literal, Sequence

import numpy as np

from desmon.errors import SignalError
from desmon.model.actions import ACTIONS, GRASP, HOLD, IDLE, MOVE_BASE, RELEASE, ROTATE_CCW, ROTATE_CW

__all__ = [
    "N_PADS",
    "PAD_NAMES",
    "PAD_ROWS",
    "PAD_COLS",
    "MAX_ROWS",
    "FULL_SCALE",
    "UP",
    "DOWN",
    "PULLED",
    "GRAVITATIONAL",
    "SignalParams",
    "Segment",
    "SlipEvent",
    "SensorFault",
    "SlipTruth",
    "WrenchBlock",
    "TactileBlock",
    "Batch",
    "MissionSignals",
    "wrench_indices",
    "tactile_nominal_indices",
    "frame_moments",
    "simulate_batch",
    "render_pad_moments",
    "render_rows",
]

N_PADS: Final = 6
PAD_NAMES: Final = ("thumb_prox", "thumb_dist", "f1_prox", "f1_dist", "f2_prox", "f2_dist")
PAD_ROWS: Final = (14, 13, 14, 13, 14, 13)
PAD_COLS: Final = 6
MAX_ROWS: Final = 14
FULL_SCALE: Final = 3500
CELL_PITCH_MM: Final = 3.4
G_ACCEL: Final = 9.81

UP: Final = "up"
DOWN: Final = "down"
PULLED: Final = "pulled"
GRAVITATIONAL: Final = "gravitational"

WrenchSource = Literal["lwr_estimate", "wrist_ft"]
Arr = np.ndarray
Params = dict[str, Arr]

# Seed-sequence tags: one independent stream per purpose.
_TAG_PARAMS: Final = 0
_TAG_WRENCH: Final = 1
_TAG_TACTILE: Final = 2
_TAG_JITTER: Final = 3

#: Samples per noise block of the wrench stream / frames per tactile render block.
WRENCH_BLOCK: Final = 1024
TACTILE_BLOCK: Final = 256
JITTER_BLOCK: Final = 1024
#: Rendered tactile blocks kept per mission (a sim detector's quiet chunk spans ~4).
TACTILE_CACHE: Final = 16
#: Seconds of an object-in-hand episode rendered ahead of a tactile request.
PREFETCH_S: Final = 40.0


@dataclass(frozen=True, slots=True)
class SignalParams:
    """Model parameters (research note §4). Calibrated values are marked there [CALIB]."""

    tactile_rate: float = 30.0
    tactile_jitter: float = 0.002
    tactile_jitter_clip: float = 0.008
    noise_counts: float = 4.0
    deadband: float = 5.0
    peak_lo: float = 100.0
    peak_hi: float = 600.0
    sigma_lo: float = 0.5
    sigma_hi: float = 1.0
    force_noise_lwr: float = 0.3
    force_noise_ft: float = 0.05
    ft_coupling_scale: float = 0.2  # a wrist F/T does not misattribute arm inertia [ASSUME]
    creep_max: float = 0.005
    creep_tau: float = 10.0
    # grasp
    grasp_drift: float = 1.2
    grasp_on: tuple[float, float] = (0.2, 0.6)
    grasp_ramp: tuple[float, float] = (0.2, 0.6)
    grasp_amp: float = 0.8
    grasp_delay: tuple[float, float] = (0.05, 0.3)
    grasp_bump: tuple[float, float] = (0.2, 0.5)
    # release
    release_drift: float = 1.6
    release_off: tuple[float, float] = (0.2, 0.6)
    release_ramp: tuple[float, float] = (0.05, 0.3)
    release_amp: float = 0.45
    release_start: tuple[float, float] = (0.1, 0.5)
    release_bump: tuple[float, float] = (0.2, 0.5)
    # rotate
    rot_arc_ccw: tuple[float, float] = (0.7, 2.4)
    rot_arc_cw: tuple[float, float] = (1.0, 3.0)
    rot_amp_ccw: float = 0.6
    rot_amp_cw: float = 0.7
    rot_start: tuple[float, float] = (0.1, 0.3)
    rot_dur: tuple[float, float] = (0.5, 1.0)
    # move_base
    base_leg: float = 0.2
    base_start: tuple[float, float] = (0.1, 0.3)
    base_pause: float = 0.5
    base_amax: tuple[float, float] = (0.4, 1.0)
    base_gain: tuple[float, float] = (0.5, 2.5)
    base_kv: float = 2.0
    base_fv: tuple[float, float] = (3.0, 12.0)
    base_settle_p: float = 0.02
    base_settle_jump: tuple[float, float] = (0.6, 1.0)
    # slips
    slip_dist_mm: tuple[float, float] = (3.0, 12.0)
    slip_time: tuple[float, float] = (0.1, 0.4)
    slip_jerks: int = 3
    slip_rho: tuple[float, float] = (0.5, 1.0)
    slip_fs: tuple[float, float] = (1.6, 5.0)
    slip_rate: tuple[float, float] = (5.0, 30.0)
    slip_k: tuple[float, float] = (0.5, 0.9)
    slip_tau_d: tuple[float, float] = (0.05, 0.2)
    slip_extra: tuple[float, float] = (0.0, 0.15)
    object_mass: tuple[float, float] = (0.3, 0.6)


DEFAULT_PARAMS: Final = SignalParams()


@dataclass(frozen=True, slots=True)
class Segment:
    """One action context on the mission timeline: ``context`` from ``start`` for ``duration`` seconds."""

    context: str
    start: float
    duration: float

    @property
    def end(self) -> float:
        return self.start + self.duration


@dataclass(frozen=True, slots=True)
class SlipEvent:
    """A slip: object *motion* starts at ``onset`` (s); ``direction`` up/down; ``kind`` pulled/gravitational."""

    onset: float
    direction: str = DOWN
    kind: str = PULLED


@dataclass(frozen=True, slots=True)
class SensorFault:
    """From ``start`` (until ``end``, default forever) ``sensor`` ('wrench'|'tactile') fails.

    ``mode``: ``'silent'`` (no samples at all), ``'stuck'`` (repeats its last good sample)
    or ``'zero'`` (outputs zeros).
    """

    sensor: str
    start: float
    mode: str = "silent"
    end: float = math.inf


@dataclass(frozen=True, slots=True)
class SlipTruth:
    """Ground truth of one slip as rendered: motion onset, load onset, direction, kind and
    the sign the tared wrench takes (+1 up / -1 down)."""

    motion_onset: float
    load_onset: float
    direction: str
    kind: str
    force_sign: int


@dataclass(frozen=True, slots=True)
class WrenchBlock:
    """Wrench samples: ``index`` (grid index k, t = k / rate), ``times`` (s), ``values`` (N, + = up)."""

    index: Arr
    times: Arr
    values: Arr


@dataclass(frozen=True, slots=True)
class TactileBlock:
    """Tactile frames: ``index`` (frame number), ``times`` (s, jittered), ``moments`` ``(K, 6, 3)``
    and, if requested, ``frames`` ``(K, 6, 14, 6)`` int16."""

    index: Arr
    times: Arr
    moments: Arr
    frames: Arr | None = None


# --------------------------------------------------------------------------- helpers


def _u(rng: np.random.Generator, lohi: tuple[float, float], size: int | tuple[int, ...]) -> Arr:
    return rng.uniform(lohi[0], lohi[1], size)


def half_sine(t: Arr, t0: Arr, width: Arr) -> Arr:
    """``sin(pi (t - t0) / width)`` on ``[t0, t0 + width]``, zero elsewhere (broadcasting)."""
    u = (t - t0) / width
    return np.where((u >= 0.0) & (u <= 1.0), np.sin(np.pi * np.clip(u, 0.0, 1.0)), 0.0)


def _jerky(t: Arr, t0: Arr, width: Arr, jerks: Arr | int) -> Arr:
    """Progress in ``jerks`` discrete steps: ``floor(N u) / N`` with ``u = clip((t - t0)/width, 0, 1)``."""
    u = np.clip((t - t0) / width, 0.0, 1.0)
    return np.floor(jerks * u) / jerks


def base_profile(tau: Arr, a_max: Arr, leg: float, pause: float) -> tuple[Arr, Arr]:
    """Base acceleration and speed for the back-and-forth drive: pulses +,-, pause, -,+.

    ``tau`` is time since the drive started; each pulse lasts ``sqrt(leg / a_max)``.
    """
    ta = np.sqrt(leg / a_max)
    t2 = tau - 2.0 * ta - pause
    c1 = (tau >= 0) & (tau < ta)
    c2 = (tau >= ta) & (tau < 2 * ta)
    c3 = (t2 >= 0) & (t2 < ta)
    c4 = (t2 >= ta) & (t2 < 2 * ta)
    acc = np.select([c1, c2, c3, c4], [a_max, -a_max, -a_max, a_max], 0.0)
    vel = np.select([c1, c2, c3, c4], [a_max * tau, a_max * (2 * ta - tau), -a_max * t2, -a_max * (2 * ta - t2)], 0.0)
    return acc, vel


def base_duration(a_max: float, p: SignalParams = DEFAULT_PARAMS) -> float:
    """Length of the drive (from its start) for a given peak acceleration."""
    return 4.0 * math.sqrt(p.base_leg / a_max) + p.base_pause


# --------------------------------------------------------------------------- parameter draws


def draw_contact(rng: np.random.Generator, n: int, two_finger: Arr, p: SignalParams = DEFAULT_PARAMS) -> Params:
    """Per-pad contact constants for ``n`` grasps (research note §3.2; [BAG]).

    Three-finger grasps touch 3-4 pads, two-finger grasps 2-3; pads not in contact
    get amplitude 0.
    """
    rows = np.asarray(PAD_ROWS, dtype=float)
    order = np.argsort(rng.random((n, N_PADS)), axis=1)
    rank = np.argsort(order, axis=1)
    m = np.where(two_finger, rng.integers(2, 4, n), rng.integers(3, 5, n))
    contact = rank < m[:, None]
    amp = np.exp(rng.uniform(math.log(p.peak_lo), math.log(p.peak_hi), (n, N_PADS)))
    return {
        "contact": contact,
        "A": np.where(contact, amp, 0.0),
        "sy": _u(rng, (p.sigma_lo, p.sigma_hi), (n, N_PADS)),
        "sx": _u(rng, (p.sigma_lo, p.sigma_hi), (n, N_PADS)),
        "y": 2.0 + rng.random((n, N_PADS)) * (rows - 5.0),  # U(2, R - 3)
        "x": _u(rng, (1.5, 3.5), (n, N_PADS)),
        "kappa": rng.uniform(0.0, p.creep_max, n),
    }


def draw_context(
    context: str, rng: np.random.Generator, n: int, contact: Arr | None, p: SignalParams = DEFAULT_PARAMS
) -> Params:
    """Random parameters of one action context for ``n`` trials (research note §3.1–3.2, §4)."""
    if context == GRASP:
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
    if context == RELEASE:
        return {
            "t_off": _u(rng, p.release_off, (n, N_PADS)),
            "ramp": _u(rng, p.release_ramp, (n, N_PADS)),
            "dy": rng.normal(0.0, p.release_drift, (n, N_PADS)),
            "dx": rng.normal(0.0, p.release_drift, (n, N_PADS)),
            "amp": rng.normal(0.0, p.release_amp, n),
            "b0": _u(rng, p.release_start, n),
            "bw": _u(rng, p.release_bump, n),
        }
    if context in (ROTATE_CCW, ROTATE_CW):
        ccw = context == ROTATE_CCW
        return {
            "t0": _u(rng, p.rot_start, n),
            "dur": _u(rng, p.rot_dur, n),
            "jerks": rng.integers(2, 5, n).astype(float),
            "arc": _u(rng, p.rot_arc_ccw if ccw else p.rot_arc_cw, n),
            "ydir": rng.normal(0.0, 0.5, n),
            "xdir": np.full(n, 1.0 if ccw else -1.0),
            "amp": rng.normal(0.0, p.rot_amp_ccw if ccw else p.rot_amp_cw, n),
        }
    if context == MOVE_BASE:
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
    if context == HOLD:
        return {}
    if context == IDLE:
        return {}
    raise SignalError(_no_signal_model(context))


def draw_slip(rng: np.random.Generator, n: int, p: SignalParams = DEFAULT_PARAMS) -> Params:
    """Slip parameters (research note §3.1 slip load, §3.2 slip overlay)."""
    return {
        "D": _u(rng, p.slip_dist_mm, n) / CELL_PITCH_MM,
        "T": _u(rng, p.slip_time, n),
        "rho": _u(rng, p.slip_rho, n),
        "Fs": _u(rng, p.slip_fs, n),
        "r": _u(rng, p.slip_rate, n),
        "k": _u(rng, p.slip_k, n),
        "tau_d": _u(rng, p.slip_tau_d, n),
        "extra": _u(rng, p.slip_extra, n),
        "mass": _u(rng, p.object_mass, n),
    }


def slip_load_onset(t_s: Arr, sp: Params, gravitational: Arr) -> Arr:
    """Time the wrist load starts changing: ``t_s - F_s / r`` for pulled slips, ``t_s`` for gravitational."""
    return np.where(gravitational, t_s, t_s - sp["Fs"] / sp["r"])


# --------------------------------------------------------------------------- force kernels


def context_force(context: str, t_rel: Arr, cp: Params, p: SignalParams, coupling: float) -> Arr:
    """Context disturbance ``d_ctx`` along the slip axis (N) at ``t_rel`` seconds into the action.

    ``cp`` arrays have shape ``(n,)``; ``t_rel`` ``(n, K)``. Zero for hold / idle.
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


def slip_force(t: Arr, t_s: Arr, sign: Arr, gravitational: Arr, sp: Params) -> Arr:
    """Slip load on the wrist (N) for slips with motion onset ``t_s`` and motion sign ``sign`` (+1 up).

    Pulled: linear build-up ``r (t - t_p)`` until ``t_s``, kinetic ``k F_s`` while sliding,
    exponential release after ``t_e``; same sign as the motion. Gravitational: no
    build-up; while sliding the wrist is unloaded by ``m g (1 - k)``, so the tared
    signal moves *opposite* to the motion.
    """
    c = {k: v[:, None] for k, v in sp.items()}
    ts = t_s[:, None]
    s = sign[:, None]
    grav = gravitational[:, None]
    t_e = ts + c["T"] + c["extra"]
    slide = np.where(grav, -c["mass"] * G_ACCEL * (1.0 - c["k"]), c["k"] * c["Fs"])
    t_p = ts - c["Fs"] / c["r"]
    build = np.where(grav, 0.0, np.where((t >= t_p) & (t < ts), c["r"] * (t - t_p), 0.0))
    during = np.where((t >= ts) & (t < t_e), slide, 0.0)
    after = np.where(t >= t_e, slide * np.exp(-np.maximum(t - t_e, 0.0) / c["tau_d"]), 0.0)
    return s * (build + during + after)


# --------------------------------------------------------------------------- tactile kernels


def context_tactile(context: str, t_rel: Arr, cp: Params, p: SignalParams) -> tuple[Arr, Arr, Arr]:
    """Pressure factor and centre offsets (rows, columns) per pad, shapes broadcastable to ``(n, K, 6)``.

    ``t_rel`` ``(n, K, 1)`` is clipped by the caller to ``[0, duration]`` so that the
    state at the end of an action persists afterwards.
    """
    one = np.ones(1)
    zero = np.zeros(1)
    if context == GRASP:
        g = np.clip((t_rel - cp["t_on"][:, None, :]) / cp["ramp"][:, None, :], 0.0, 1.0)
        return g, cp["dy"][:, None, :] * (1 - g), cp["dx"][:, None, :] * (1 - g)
    if context == RELEASE:
        g = 1.0 - np.clip((t_rel - cp["t_off"][:, None, :]) / cp["ramp"][:, None, :], 0.0, 1.0)
        return g, cp["dy"][:, None, :] * (1 - g), cp["dx"][:, None, :] * (1 - g)
    if context in (ROTATE_CCW, ROTATE_CW):
        q = _jerky(t_rel, cp["t0"][:, None, None], cp["dur"][:, None, None], cp["jerks"][:, None, None])
        arc = cp["arc"][:, None, None] * q
        return one, arc * cp["ydir"][:, None, None], arc * cp["xdir"][:, None, None]
    if context == MOVE_BASE:
        acc, _ = base_profile(t_rel - cp["start"][:, None, None], cp["a_max"][:, None, None], p.base_leg, p.base_pause)
        rel = acc / cp["a_max"][:, None, None]
        jump = cp["settle"][:, None, None] * cp["settle_jump"][:, None, None] * (t_rel >= cp["settle_t"][:, None, None])
        return 1.0 + 0.03 * rel, 0.05 * rel + jump, zero
    return one, zero, zero


def hold_creep(t_rel: Arr, kappa: Arr, p: SignalParams) -> Arr:
    """Slow pressure creep while holding, saturating at ``1 + kappa * tau``."""
    return 1.0 + kappa[:, None, None] * p.creep_tau * (1.0 - np.exp(-t_rel / p.creep_tau))


@dataclass(frozen=True, slots=True)
class _Episode:
    """An object-in-hand interval: contact constants, its action segments and slips."""

    start: float
    end: float
    contact: Params
    segments: tuple[tuple[str, float, float, Params], ...]
    slips: tuple[tuple[Arr, Arr, Params], ...]  # (t_s (n,), sign (n,), slip params)


def episode_pad_state(t: Arr, ep: _Episode, p: SignalParams) -> tuple[Arr, Arr, Arr]:
    """Amplitude, row centre and column centre of every pad, each ``(n, K, 6)``, at times ``t`` ``(n, K)``."""
    c = ep.contact
    amp = np.broadcast_to(c["A"][:, None, :], t.shape + (N_PADS,)).copy()
    yc = np.broadcast_to(c["y"][:, None, :], amp.shape).copy()
    xc = np.broadcast_to(c["x"][:, None, :], amp.shape).copy()
    t3 = t[..., None]
    for context, start, dur, cp in ep.segments:
        tr = np.clip(t3 - start, 0.0, dur)
        if context == HOLD:
            amp *= hold_creep(tr, c["kappa"], p)
            continue
        if context == IDLE:
            continue
        fac, dy, dx = context_tactile(context, tr, cp, p)
        amp *= fac
        yc += dy
        xc += dx
    for t_s, sign, sp in ep.slips:
        q = _jerky(t3, t_s[:, None, None], sp["T"][:, None, None], p.slip_jerks)
        amp *= 1.0 - (1.0 - sp["rho"][:, None, None]) * q
        yc += sign[:, None, None] * sp["D"][:, None, None] * q
    inside = ((t3 >= ep.start) & (t3 < ep.end))
    return np.where(inside, amp, 0.0), yc, xc


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
    static = bool(np.all(yc == yc[:, :1])) and bool(np.all(xc == xc[:, :1])) and n == 1
    if static:
        ey = np.exp(-((ii - yc[0, 0]) ** 2) / (2.0 * sy[0] ** 2))
        ex = np.exp(-((jj - xc[0, 0]) ** 2) / (2.0 * sx[0] ** 2))
        tmpl = (ey[:, None] * ex[None, :]).ravel()
        sup = np.flatnonzero(tmpl * amp.max() >= p.deadband)
        mu = amp[..., None] * tmpl[sup]  # (n, K, s)
        mask = mu >= p.deadband
        pos = np.flatnonzero(mask)
        s = sup.size
        frame = pos // s if s else pos
        cell = sup[pos % s] if s else pos
    else:
        ey = np.exp(-((ii - yc[..., None]) ** 2) / (2.0 * sy[:, None, None] ** 2))
        ex = np.exp(-((jj - xc[..., None]) ** 2) / (2.0 * sx[:, None, None] ** 2))
        mu = amp[..., None, None] * (ey[..., :, None] * ex[..., None, :])
        mask = mu >= p.deadband
        pos = np.flatnonzero(mask)
        frame = pos // cells
        cell = pos % cells
    mu_on = mu.reshape(-1)[pos]
    vals = np.clip(np.rint(mu_on + p.noise_counts * normals(pos.size)), 0.0, FULL_SCALE)
    nk = n * k
    s_sum = np.bincount(frame, weights=vals, minlength=nk).reshape(n, k)
    s_i = np.bincount(frame, weights=vals * (cell // PAD_COLS), minlength=nk).reshape(n, k)
    s_j = np.bincount(frame, weights=vals * (cell % PAD_COLS), minlength=nk).reshape(n, k)
    extra = (frame * cells + cell, vals) if want_values else None
    return s_sum, s_i, s_j, extra


_ROW_OK: Final = np.arange(MAX_ROWS)[None, :] < np.asarray(PAD_ROWS)[:, None]  # (6, 14) cells that exist
_II: Final = np.arange(MAX_ROWS, dtype=float)
_JJ: Final = np.arange(PAD_COLS, dtype=float)
_CELL_ROW: Final = np.repeat(_II, PAD_COLS)  # flat cell -> row
_CELL_COL: Final = np.tile(_JJ, MAX_ROWS)  # flat cell -> column


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

    Consecutive rows with the same pad and centre share one template ``ey_i * ex_j``
    (a hold, a move_base phase, a jerk of a slip), and only the template's cells that
    can reach the dead-band at the run's peak amplitude are evaluated per frame.
    """
    n = amp.size
    if n == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(0)
    change = np.empty(n, dtype=bool)
    change[0] = True
    np.not_equal(pad[1:], pad[:-1], out=change[1:])
    change[1:] |= (yc[1:] != yc[:-1]) | (xc[1:] != xc[:-1]) | (sy[1:] != sy[:-1]) | (sx[1:] != sx[:-1])
    starts = np.flatnonzero(change)
    run = np.cumsum(change) - 1
    ey = np.exp(-((_II - yc[starts][:, None]) ** 2) / (2.0 * sy[starts][:, None] ** 2))
    ex = np.exp(-((_JJ - xc[starts][:, None]) ** 2) / (2.0 * sx[starts][:, None] ** 2))
    ey *= _ROW_OK[pad[starts]]  # rows a distal pad does not have read nothing
    tmpl = (ey[:, :, None] * ex[:, None, :]).reshape(-1)
    # a cell below the dead-band at the run's peak amplitude is below it in every frame
    peak = np.maximum.reduceat(amp, starts)
    sup_flat = np.flatnonzero(tmpl * np.repeat(peak, MAX_ROWS * PAD_COLS) >= p.deadband)
    sup_tmpl = tmpl[sup_flat]
    sup_cell = sup_flat % (MAX_ROWS * PAD_COLS)
    count = np.bincount(sup_flat // (MAX_ROWS * PAD_COLS), minlength=starts.size)
    offset = np.cumsum(count) - count
    per_row = count[run]
    first = np.cumsum(per_row) - per_row
    idx = np.arange(int(first[-1] + per_row[-1])) - np.repeat(first - offset[run], per_row)
    mu = np.repeat(amp, per_row)
    mu *= sup_tmpl[idx]
    hit = mu >= p.deadband
    keep = np.flatnonzero(hit)
    # kept cells per row: positions of the row starts among the kept cells
    kept = np.diff(np.searchsorted(keep, np.append(first, idx.size)))
    return kept, sup_cell[idx[keep]], mu[keep]


def frame_moments(frames: Arr) -> Arr:
    """Per-pad moments ``(..., 6, 3) = (sum P, sum i P, sum j P)`` of frames ``(..., 6, 14, 6)``."""
    f = np.asarray(frames, dtype=float)
    ii = np.arange(MAX_ROWS, dtype=float)
    jj = np.arange(PAD_COLS, dtype=float)
    s = f.sum(axis=(-1, -2))
    si = (f.sum(axis=-1) * ii).sum(axis=-1)
    sj = (f.sum(axis=-2) * jj).sum(axis=-1)
    return np.stack([s, si, sj], axis=-1)


# --------------------------------------------------------------------------- grids


def wrench_indices(t0: float, t1: float, rate: float) -> Arr:
    """Indices ``k`` of the fixed-rate wrench grid ``t = k / rate`` with ``t0 <= t < t1``."""
    k0 = max(0, math.floor(t0 * rate) - 1)
    k1 = max(k0, math.ceil(t1 * rate) + 1)
    k = np.arange(k0, k1, dtype=np.int64)
    tk = k / rate
    return k[(tk >= t0) & (tk < t1)]


def tactile_nominal_indices(t0: float, t1: float, rate: float, slack: float) -> Arr:
    """Candidate frame numbers whose jittered time may fall in ``[t0, t1)`` (``slack`` = max |jitter|)."""
    k0 = max(0, math.floor((t0 - slack) * rate))
    k1 = max(k0, math.ceil((t1 + slack) * rate) + 1)
    return np.arange(k0, k1, dtype=np.int64)


def _block_rng(seed: int, tag: int, block: int) -> np.random.Generator:
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence([seed, tag, block])))


# --------------------------------------------------------------------------- mission signals


def _no_signal_model(context: str) -> str:
    """The signal models exist for the built-in actions only; a model's own action is
    rendered as the built-in it is declared like (``desmon.sim.world.like_segments``)."""
    return (
        f"unknown context {context!r}: signal models exist for the built-in actions ({', '.join(ACTIONS)}); "
        "render a model's own action as the built-in it is like (SystemModel.like)"
    )


def _check_contexts(segments: Sequence[Segment]) -> None:
    prev_end = 0.0
    for i, s in enumerate(segments):
        if s.context not in ACTIONS:
            raise SignalError(f"segment {i}: {_no_signal_model(s.context)}")
        if not (s.duration > 0 and math.isfinite(s.duration)):
            raise SignalError(f"segment {i} ({s.context}): duration {s.duration!r} must be a positive finite number")
        if s.start < prev_end - 1e-9 or s.start < 0:
            raise SignalError(
                f"segment {i} ({s.context}) starts at {s.start!r} before the previous one ends ({prev_end!r}); "
                "give segments in time order without overlap, starting at t >= 0"
            )
        prev_end = s.end


class MissionSignals:
    """Deterministic wrench and tactile streams for a whole mission (the SimPy world's sensor source).

    Parameters
    ----------
    segments:
        ``Segment`` objects or ``(context, start_s, duration_s)`` tuples, in time order,
        contexts from :mod:`desmon.model.actions`. Gaps between segments count as idle
        (nothing in hand). A grasp starts an object-in-hand episode, the end of a release
        (or idle) ends it; a mission that starts with another risky context starts with
        the object already in the hand.
    slips:
        ``SlipEvent`` objects or ``(onset_s, direction, kind)`` tuples. ``onset`` is slip
        *motion* onset; a pulled slip loads the wrist up to 1 s earlier. A slip must fall
        inside an episode (object in hand).
    seed:
        Every random quantity derives from it: per-segment and per-slip parameters are
        drawn up front at construction; per-sample noise and tactile jitter come from
        generators keyed by ``(seed, stream, block number)``, so a sample depends only on
        its index, never on how requests are chunked.
    wrench_source / wrench_rate:
        ``"lwr_estimate"`` (default, 50 Hz, sigma 0.3 N, base inertia leaks into the
        estimate) or ``"wrist_ft"`` (100–1000 Hz, sigma 0.05 N, weak coupling).
    faults:
        ``SensorFault`` list (silent / stuck / zero from a time on).
    two_finger:
        Grasp type per episode; default alternates three-finger / two-finger.

    Sampling
    --------
    ``wrench(t0, t1)`` / ``tactile(t0, t1)`` return every sample whose time lies in
    ``[t0, t1)``; ``wrench_at(index)`` / ``tactile_at(index)`` return samples by grid
    index. Wrench sample ``k`` is at ``k / wrench_rate``; tactile frame ``k`` at
    ``k / 30 + jitter_k`` (jitter N(0, 2 ms) clipped to +-8 ms, so frames stay ordered).
    """

    def __init__(
        self,
        segments: Sequence[Segment | tuple[str, float, float]],
        slips: Sequence[SlipEvent | tuple[float, str, str]] = (),
        *,
        seed: int = 0,
        wrench_source: WrenchSource = "lwr_estimate",
        wrench_rate: float | None = None,
        faults: Sequence[SensorFault] = (),
        params: SignalParams = DEFAULT_PARAMS,
        two_finger: Sequence[bool] | None = None,
    ) -> None:
        if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0:
            raise SignalError(f"seed {seed!r} must be a non-negative integer")
        segs = tuple(s if isinstance(s, Segment) else Segment(str(s[0]), float(s[1]), float(s[2])) for s in segments)
        _check_contexts(segs)
        evs = tuple(s if isinstance(s, SlipEvent) else SlipEvent(float(s[0]), str(s[1]), str(s[2])) for s in slips)
        for e in evs:
            if e.direction not in (UP, DOWN):
                raise SignalError(f"slip at {e.onset}: direction {e.direction!r} must be 'up' or 'down'")
            if e.kind not in (PULLED, GRAVITATIONAL):
                raise SignalError(f"slip at {e.onset}: kind {e.kind!r} must be 'pulled' or 'gravitational'")
        if wrench_source == "lwr_estimate":
            rate = 50.0 if wrench_rate is None else float(wrench_rate)
            sigma = params.force_noise_lwr
            coupling = 1.0
        elif wrench_source == "wrist_ft":
            rate = 500.0 if wrench_rate is None else float(wrench_rate)
            if not 100.0 <= rate <= 1000.0:
                raise SignalError(f"wrench_rate {rate!r} Hz: a wrist_ft streams at 100-1000 Hz; pick a rate in that range")
            sigma = params.force_noise_ft
            coupling = params.ft_coupling_scale
        else:
            raise SignalError(f"wrench_source {wrench_source!r}: use 'lwr_estimate' or 'wrist_ft'")
        if not (rate > 0 and math.isfinite(rate)):
            raise SignalError(f"wrench_rate {rate!r} must be a positive number of Hz")
        for f in faults:
            if f.sensor not in ("wrench", "tactile") or f.mode not in ("silent", "stuck", "zero") or not f.end > f.start:
                raise SignalError(
                    f"fault {f!r}: sensor must be 'wrench' or 'tactile', mode 'silent', 'stuck' or 'zero', end > start"
                )
        self.seed = int(seed)
        self.segments = segs
        self.slips = evs
        self.params = params
        self.wrench_source = wrench_source
        self.wrench_rate = rate
        self.tactile_rate = params.tactile_rate
        self.faults = tuple(faults)
        self._sigma = sigma
        self._coupling = coupling
        rng = _block_rng(self.seed, _TAG_PARAMS, 0)
        # per-segment parameters, drawn in timeline order
        self._episodes: list[_Episode] = []
        seg_params: list[Params] = []
        ep_start: float | None = None
        ep_contact: Params | None = None
        ep_segs: list[tuple[str, float, float, Params]] = []
        n_ep = 0

        def close(end: float) -> None:
            nonlocal ep_start, ep_contact, ep_segs
            if ep_start is not None and ep_contact is not None:
                self._episodes.append(_Episode(ep_start, end, ep_contact, tuple(ep_segs), ()))
            ep_start, ep_contact, ep_segs = None, None, []

        for s in segs:
            if ep_start is not None and ep_segs and s.start > ep_segs[-1][1] + ep_segs[-1][2] + 1e-9:
                close(ep_segs[-1][1] + ep_segs[-1][2])  # a gap: the hand is empty
            if s.context == IDLE:
                close(s.start)
                seg_params.append({})
                continue
            if s.context == GRASP or ep_start is None:
                close(s.start)
                tf = (n_ep % 2 == 1) if two_finger is None else bool(two_finger[n_ep % len(two_finger)])
                ep_contact = draw_contact(rng, 1, np.array([tf]), params)
                ep_start = s.start
                n_ep += 1
            cp = draw_context(s.context, rng, 1, ep_contact["contact"] if ep_contact else None, params)
            seg_params.append(cp)
            ep_segs.append((s.context, s.start, s.duration, cp))
            if s.context == RELEASE:
                close(s.end)
        if ep_start is not None and ep_segs:
            close(ep_segs[-1][1] + ep_segs[-1][2])
        self._seg_params = tuple(seg_params)
        # slips: parameters and episode membership
        truths: list[SlipTruth] = []
        self._slip_arrays: list[tuple[Arr, Arr, Arr, Params]] = []
        ep_slips: dict[int, list[tuple[Arr, Arr, Params]]] = {}
        for e in sorted(evs, key=lambda x: x.onset):
            idx = next((i for i, ep in enumerate(self._episodes) if ep.start <= e.onset < ep.end), None)
            if idx is None:
                raise SignalError(
                    f"slip at t={e.onset}: no object is in the hand then; place slips inside grasp..release episodes"
                )
            sp = draw_slip(rng, 1, params)
            t_s = np.array([e.onset])
            sign = np.array([1.0 if e.direction == UP else -1.0])
            grav = np.array([e.kind == GRAVITATIONAL])
            self._slip_arrays.append((t_s, sign, grav, sp))
            ep_slips.setdefault(idx, []).append((t_s, sign, sp))
            t_p = float(slip_load_onset(t_s, sp, grav)[0])
            fsign = int(sign[0]) * (-1 if e.kind == GRAVITATIONAL else 1)
            truths.append(SlipTruth(e.onset, t_p, e.direction, e.kind, fsign))
        self._episodes = [replace(ep, slips=tuple(ep_slips.get(i, ()))) for i, ep in enumerate(self._episodes)]
        self._ep_starts = np.array([ep.start for ep in self._episodes])
        self.slip_truth: tuple[SlipTruth, ...] = tuple(truths)
        self._seg_starts = np.array([s.start for s in segs])
        self._seg_ends = np.array([s.end for s in segs])
        self._wcache: dict[int, Arr] = {}
        self._tcache: dict[tuple[int, bool], tuple[Arr, Arr, Arr | None]] = {}
        self._jcache: dict[int, Arr] = {}

    # ------------------------------------------------------------------ wrench
    @property
    def end_time(self) -> float:
        """End of the last segment."""
        return float(self._seg_ends[-1]) if len(self.segments) else 0.0

    def _wrench_block(self, b: int) -> Arr:
        hit = self._wcache.get(b)
        if hit is not None:
            return hit
        k = np.arange(b * WRENCH_BLOCK, (b + 1) * WRENCH_BLOCK, dtype=np.int64)
        t = (k / self.wrench_rate)[None, :]
        val = self._sigma * _block_rng(self.seed, _TAG_WRENCH, b).standard_normal(WRENCH_BLOCK)[None, :]
        t_lo, t_hi = float(t[0, 0]), float(t[0, -1])
        i0 = int(np.searchsorted(self._seg_ends, t_lo, side="right"))
        i1 = int(np.searchsorted(self._seg_starts, t_hi, side="right"))
        for i in range(i0, i1):
            s = self.segments[i]
            if s.context in (HOLD, IDLE):
                continue
            inside = (t >= s.start) & (t < s.end)
            val = val + np.where(inside, context_force(s.context, t - s.start, self._seg_params[i], self.params, self._coupling), 0.0)
        for t_s, sign, grav, sp in self._slip_arrays:
            if t_hi < float(t_s[0]) - 1.5 or t_lo > float(t_s[0]) + 2.0:
                continue
            val = val + slip_force(t, t_s, sign, grav, sp)
        out = val[0]
        if len(self._wcache) >= 8:
            del self._wcache[next(iter(self._wcache))]
        self._wcache[b] = out
        return out

    def _wrench_clean(self, k: Arr) -> Arr:
        out = np.empty(k.shape)
        if k.size == 0:
            return out
        b0 = int(k[0]) // WRENCH_BLOCK
        if k.ndim == 1 and int(k[-1]) // WRENCH_BLOCK == b0 and int(k.min()) // WRENCH_BLOCK == b0:
            return self._wrench_block(b0)[k - b0 * WRENCH_BLOCK]
        blocks = k // WRENCH_BLOCK
        for b in np.unique(blocks):
            sel = blocks == b
            out[sel] = self._wrench_block(int(b))[k[sel] - b * WRENCH_BLOCK]
        return out

    def wrench_at(self, index: Arr) -> WrenchBlock:
        """Wrench samples for grid indices ``index`` (int array, >= 0), faults applied."""
        k = np.asarray(index, dtype=np.int64)
        t = k / self.wrench_rate
        v = self._wrench_clean(k)
        keep = np.ones(k.shape, dtype=bool)
        for f in self.faults:
            if f.sensor != "wrench":
                continue
            hit = (t >= f.start) & (t < f.end)
            if f.mode == "silent":
                keep &= ~hit
            elif f.mode == "zero":
                v = np.where(hit, 0.0, v)
            else:
                k_last = max(0, math.ceil(f.start * self.wrench_rate - 1e-9) - 1)
                v = np.where(hit, self._wrench_clean(np.array([k_last]))[0], v)
        return WrenchBlock(k[keep], t[keep], v[keep])

    def wrench(self, t0: float, t1: float) -> WrenchBlock:
        """All wrench samples with ``t0 <= t < t1``."""
        return self.wrench_at(wrench_indices(t0, t1, self.wrench_rate))

    # ------------------------------------------------------------------ tactile
    def _jitter(self, k: Arr) -> Arr:
        out = np.empty(k.shape)
        p = self.params
        if k.size and k.ndim == 1 and int(k.min()) // JITTER_BLOCK == int(k.max()) // JITTER_BLOCK:
            blocks = np.full(1, int(k[0]) // JITTER_BLOCK)
            uniq = blocks
        else:
            blocks = k // JITTER_BLOCK
            uniq = np.unique(blocks)
        for b in uniq:
            arr = self._jcache.get(int(b))
            if arr is None:
                g = _block_rng(self.seed, _TAG_JITTER, int(b))
                arr = np.clip(g.normal(0.0, p.tactile_jitter, JITTER_BLOCK), -p.tactile_jitter_clip, p.tactile_jitter_clip)
                if len(self._jcache) >= 8:
                    del self._jcache[next(iter(self._jcache))]
                self._jcache[int(b)] = arr
            if uniq.size == 1 and blocks.size == 1:
                return arr[k - int(b) * JITTER_BLOCK]
            sel = blocks == b
            out[sel] = arr[k[sel] - b * JITTER_BLOCK]
        return out

    def tactile_times(self, index: Arr) -> Arr:
        """Jittered time of each frame number."""
        k = np.asarray(index, dtype=np.int64)
        return k / self.tactile_rate + self._jitter(k)

    def _tactile_block(self, b: int, frames: bool) -> tuple[Arr, Arr, Arr | None]:
        hit = self._tcache.get((b, frames))
        if hit is not None:
            return hit
        return self._render_blocks([b], frames)[0]

    def _render_blocks(self, blocks: Sequence[int], frames: bool) -> list[tuple[Arr, Arr, Arr | None]]:
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
        t = self.tactile_times((barr[:, None] * B + np.arange(B, dtype=np.int64)[None, :]).reshape(-1))
        nf = t.size
        mom = np.zeros((nf, N_PADS, 3))
        fr = np.zeros((nf, N_PADS, MAX_ROWS, PAD_COLS), dtype=np.int16) if frames else None
        # units: (block, episode) frame ranges, in draw order
        units: list[tuple[int, int]] = []
        by_ep: dict[int, list[tuple[int, int]]] = {}
        for i in range(nb):
            tb = t[i * B : (i + 1) * B]
            first = int(np.searchsorted(self._ep_starts, tb[0], side="right")) - 1
            for ei in range(max(first, 0), len(self._episodes)):
                ep = self._episodes[ei]
                if ep.start > tb[-1]:
                    break
                lo = int(np.searchsorted(tb, ep.start, side="left"))
                hi = int(np.searchsorted(tb, ep.end, side="left"))
                if hi > lo:
                    units.append((i * B + lo, i * B + hi))
                    by_ep.setdefault(ei, []).append((i * B + lo, i * B + hi))
        if units:
            amp = np.zeros((nf, N_PADS))
            yc = np.zeros((nf, N_PADS))
            xc = np.zeros((nf, N_PADS))
            sy = np.ones((nf, N_PADS))
            sx = np.ones((nf, N_PADS))
            for ei, ranges in by_ep.items():
                ep = self._episodes[ei]
                sel = np.concatenate([np.arange(lo, hi) for lo, hi in ranges])
                a, y, x = episode_pad_state(t[sel][None, :], ep, self.params)
                amp[sel], yc[sel], xc[sel] = a[0], y[0], x[0]
                sy[sel] = ep.contact["sy"][0]
                sx[sel] = ep.contact["sx"][0]
            # rows (unit, pad, frame)
            f0 = np.array([u[0] for u in units], dtype=np.int64)
            ln = np.array([u[1] - u[0] for u in units], dtype=np.int64)
            per = N_PADS * ln
            o = np.arange(int(per.sum())) - np.repeat(np.cumsum(per) - per, per)
            lr = np.repeat(ln, per)
            pad = o // lr
            frame = np.repeat(f0, per) + o % lr
            a_r = amp[frame, pad]
            on = np.flatnonzero(a_r > 0)
            pad, frame = pad[on], frame[on]
            count, cell, mu = render_rows(a_r[on], yc[frame, pad], xc[frame, pad], pad, sy[frame, pad], sx[frame, pad], self.params)
            per_block = np.bincount(frame // B, weights=count, minlength=nb).astype(np.int64)
            noise = np.empty(mu.size)
            at = 0
            for i in range(nb):
                c = int(per_block[i])
                if c:
                    noise[at : at + c] = _block_rng(self.seed, _TAG_TACTILE, int(barr[i])).standard_normal(c)
                    at += c
            vals = noise
            vals *= self.params.noise_counts
            vals += mu
            np.rint(vals, out=vals)
            np.clip(vals, 0.0, FULL_SCALE, out=vals)
            rows = np.flatnonzero(count)
            if rows.size:
                first = (np.cumsum(count) - count)[rows]
                fr_, pd_ = frame[rows], pad[rows]
                mom[fr_, pd_, 0] = np.add.reduceat(vals, first)
                mom[fr_, pd_, 1] = np.add.reduceat(vals * _CELL_ROW[cell], first)
                mom[fr_, pd_, 2] = np.add.reduceat(vals * _CELL_COL[cell], first)
            if fr is not None:
                rr = np.repeat(np.arange(count.size), count)
                fr[frame[rr], pad[rr], cell // PAD_COLS, cell % PAD_COLS] = vals.astype(np.int16)
        out = []
        for i in range(nb):
            res = (t[i * B : (i + 1) * B], mom[i * B : (i + 1) * B], fr[i * B : (i + 1) * B] if fr is not None else None)
            if len(self._tcache) >= TACTILE_CACHE:
                del self._tcache[next(iter(self._tcache))]
            self._tcache[(int(barr[i]), frames)] = res
            out.append(res)
        return out

    def _tactile_clean(self, k: Arr, frames: bool) -> tuple[Arr, Arr, Arr | None]:
        t = np.empty(k.shape)
        mom = np.empty(k.shape + (N_PADS, 3))
        if k.size and int(k.min()) // TACTILE_BLOCK == int(k.max()) // TACTILE_BLOCK:
            b0 = int(k[0]) // TACTILE_BLOCK
            bt, bm, bf = self._tactile_block(b0, frames)
            j = k - b0 * TACTILE_BLOCK
            return bt[j], bm[j], (bf[j] if bf is not None else None)
        fr = np.empty(k.shape + (N_PADS, MAX_ROWS, PAD_COLS), dtype=np.int16) if frames else None
        blocks = k // TACTILE_BLOCK
        uniq = [int(b) for b in np.unique(blocks)]
        missing = [b for b in uniq if (b, frames) not in self._tcache]
        rendered = dict(zip(missing, self._render_blocks(missing, frames))) if missing else {}
        for b in uniq:
            sel = blocks == b
            bt, bm, bf = rendered[b] if b in rendered else self._tactile_block(b, frames)
            j = k[sel] - b * TACTILE_BLOCK
            t[sel] = bt[j]
            mom[sel] = bm[j]
            if fr is not None and bf is not None:
                fr[sel] = bf[j]
        return t, mom, fr

    def tactile_at(self, index: Arr, frames: bool = False) -> TactileBlock:
        """Tactile frames by frame number (int array, >= 0), faults applied."""
        k = np.asarray(index, dtype=np.int64)
        t, mom, fr = self._tactile_clean(k, frames)
        keep = np.ones(k.shape, dtype=bool)
        for f in self.faults:
            if f.sensor != "tactile":
                continue
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
                cand = tactile_nominal_indices(f.start - 0.2, f.start, self.tactile_rate, self.params.tactile_jitter_clip)
                ct = self.tactile_times(cand)
                before = cand[ct < f.start]
                if before.size:
                    _, lm, lf = self._tactile_clean(before[-1:], frames)
                    mom[hit] = lm[0]
                    if fr is not None and lf is not None:
                        fr[hit] = lf[0]
        return TactileBlock(k[keep], t[keep], mom[keep], fr[keep] if fr is not None else None)

    def _prefetch(self, k0: int, k1: int, t1: float, frames: bool) -> None:
        """Render the blocks of frames ``k0..k1`` if any is missing, together with the blocks
        up to the end of the object-in-hand episode at ``t1`` (at most ``PREFETCH_S``
        ahead): a consumer reading a mission in chunks then pays one vectorised render
        per episode instead of one per chunk. Only *when* a block is rendered changes."""
        B = TACTILE_BLOCK
        b0, b1 = k0 // B, k1 // B
        if all((b, frames) in self._tcache for b in range(b0, b1 + 1)):
            return
        b2 = b1
        ei = int(np.searchsorted(self._ep_starts, t1, side="right")) - 1
        if ei >= 0 and self._episodes[ei].end > t1:
            end = min(self._episodes[ei].end, t1 + PREFETCH_S)
            b2 = max(b1, int(math.ceil((end + self.params.tactile_jitter_clip) * self.tactile_rate)) // B)
        if b2 - b0 + 1 > TACTILE_CACHE:
            b2 = b1
            if b2 - b0 + 1 > TACTILE_CACHE:
                return  # a long request: _tactile_clean renders it without the cache
        missing = [b for b in range(b0, b2 + 1) if (b, frames) not in self._tcache]
        self._render_blocks(missing, frames)

    def tactile(self, t0: float, t1: float, frames: bool = False) -> TactileBlock:
        """All tactile frames with ``t0 <= t < t1`` (moments always; full frames if ``frames``)."""
        cand = tactile_nominal_indices(t0, t1, self.tactile_rate, self.params.tactile_jitter_clip)
        if cand.size:
            self._prefetch(int(cand[0]), int(cand[-1]), t1, frames)
        t = self.tactile_times(cand)
        return self.tactile_at(cand[(t >= t0) & (t < t1)], frames=frames)


# --------------------------------------------------------------------------- batches (evaluation)


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
    """Render ``n`` trials of one timeline with the same kernels as :class:`MissionSignals`.

    The timeline must hold a single object-in-hand episode (optionally preceded by
    idle). With ``slip_window`` a slip with motion onset uniform in the window is
    overlaid on a fraction ``slip_fraction`` of the trials. Grasp types alternate by
    trial number (``first_trial`` keeps the alternation across chunks).
    """
    _check_contexts(timeline)
    p = params
    end = timeline[-1].end
    two = (np.arange(first_trial, first_trial + n) % 2) == 1
    contact = draw_contact(rng, n, two, p)
    seg_params = [draw_context(s.context, rng, n, contact["contact"], p) for s in timeline]
    # slips
    has_slip = np.zeros(n, dtype=bool)
    t_s = np.full(n, np.nan)
    sp = draw_slip(rng, n, p)
    if slip_window is not None:
        has_slip = rng.random(n) < slip_fraction
        t_s = np.where(has_slip, rng.uniform(slip_window[0], slip_window[1], n), np.nan)
    sign = np.full(n, 1.0 if slip_direction == UP else -1.0)
    grav = np.full(n, slip_kind == GRAVITATIONAL)
    t_s_safe = np.where(has_slip, t_s, 1e9)
    # wrench
    kf = wrench_indices(0.0, end, wrench_rate)
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
    w += slip_force(t2, t_s_safe, sign, grav, sp)
    # tactile
    kt = np.arange(0, int(math.ceil(end * p.tactile_rate)) + 1)
    jit = np.clip(rng.normal(0.0, p.tactile_jitter, (n, kt.size)), -p.tactile_jitter_clip, p.tactile_jitter_clip)
    tt = kt[None, :] / p.tactile_rate + jit
    tt = np.where(tt < 0, 0.0, tt)
    ep_start = next(s.start for s in timeline if s.context != IDLE)
    ep = _Episode(
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
    load = np.where(has_slip, slip_load_onset(t_s, sp, grav), np.nan)
    fsign = np.where(has_slip, sign * np.where(grav, -1.0, 1.0), 0.0)
    return Batch(tf, w, tt, mom, t_s, load, fsign)
