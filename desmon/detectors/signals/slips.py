"""Slip events as a signal source: the load a slipping object puts on the wrist and the way
its contact moves across the pads (research note §3.1 slip load, §3.2 slip overlay).

:func:`draw_slip` draws the physical constants of slips; :func:`slip_force` is the wrench
kernel and :func:`slip_tactile` the tactile overlay. For a mission, :func:`slip_events`
checks the caller's slips and :func:`draw_slips` places them in their episodes and draws
their constants, in onset order, from the mission's parameter generator.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Sequence

import numpy as np

from desmon.detectors.signals.common import (
    CELL_PITCH_MM,
    DEFAULT_PARAMS,
    DOWN,
    G_ACCEL,
    GRAVITATIONAL,
    PULLED,
    UP,
    Arr,
    Params,
    SignalParams,
    SlipEvent,
    SlipTruth,
    jerky,
)
from desmon.detectors.signals.common import uniform as _u
from desmon.detectors.signals.episodes import Episode
from desmon.errors import SignalError


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


def slip_tactile(t3: Arr, t_s: Arr, sign: Arr, sp: Params, p: SignalParams) -> tuple[Arr, Arr]:
    """Pressure factor and row offset of a slip's contact at times ``t3`` ``(n, K, 1)``: the
    object moves ``D`` rows in ``slip_jerks`` jerks over ``T`` seconds and loses pressure to ``rho``."""
    q = jerky(t3, t_s[:, None, None], sp["T"][:, None, None], p.slip_jerks)
    return 1.0 - (1.0 - sp["rho"][:, None, None]) * q, sign[:, None, None] * sp["D"][:, None, None] * q


@dataclass(frozen=True, slots=True)
class MissionSlip:
    """One slip of a mission as drawn: arrays of one trial (``(1,)``), its constants and episode."""

    event: SlipEvent
    t_s: Arr
    sign: Arr
    grav: Arr
    params: Params
    episode: int

    @property
    def truth(self) -> SlipTruth:
        e = self.event
        t_p = float(slip_load_onset(self.t_s, self.params, self.grav)[0])
        fsign = int(self.sign[0]) * (-1 if e.kind == GRAVITATIONAL else 1)
        return SlipTruth(e.onset, t_p, e.direction, e.kind, fsign)


def slip_events(slips: Sequence[SlipEvent | tuple[float, str, str]]) -> tuple[SlipEvent, ...]:
    """The caller's slips as :class:`SlipEvent` objects, each with a known direction and kind."""
    evs = tuple(s if isinstance(s, SlipEvent) else SlipEvent(float(s[0]), str(s[1]), str(s[2])) for s in slips)
    for e in evs:
        if e.direction not in (UP, DOWN):
            raise SignalError(f"slip at {e.onset}: direction {e.direction!r} must be 'up' or 'down'")
        if e.kind not in (PULLED, GRAVITATIONAL):
            raise SignalError(f"slip at {e.onset}: kind {e.kind!r} must be 'pulled' or 'gravitational'")
    return evs


def draw_slips(
    events: Sequence[SlipEvent], episodes: Sequence[Episode], rng: np.random.Generator, params: SignalParams = DEFAULT_PARAMS
) -> tuple[MissionSlip, ...]:
    """Each slip in onset order, with its constants drawn from ``rng`` and the episode it falls in."""
    out = []
    for e in sorted(events, key=lambda x: x.onset):
        idx = next((i for i, ep in enumerate(episodes) if ep.start <= e.onset < ep.end), None)
        if idx is None:
            raise SignalError(
                f"slip at t={e.onset}: no object is in the hand then; place slips inside grasp..release episodes"
            )
        sign = np.array([1.0 if e.direction == UP else -1.0])
        out.append(MissionSlip(e, np.array([e.onset]), sign, np.array([e.kind == GRAVITATIONAL]), draw_slip(rng, 1, params), idx))
    return tuple(out)


def with_slips(episodes: Sequence[Episode], slips: Sequence[MissionSlip]) -> tuple[Episode, ...]:
    """The episodes with their slips attached (in onset order)."""
    per: dict[int, list[tuple[Arr, Arr, Params]]] = {}
    for s in slips:
        per.setdefault(s.episode, []).append((s.t_s, s.sign, s.params))
    return tuple(replace(ep, slips=tuple(per.get(i, ()))) for i, ep in enumerate(episodes))
