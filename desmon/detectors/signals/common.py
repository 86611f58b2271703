"""Shared vocabulary of the signal sources: pad layout, directions, model parameters, the
facts a caller hands in (segments, slips, faults) or gets back (sample blocks, slip truth),
the sample grids and the timeline check.

Nothing here draws a random number; every source module builds on these names.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final, Literal, Sequence

import numpy as np

from desmon.errors import SignalError
from desmon.model.actions import ACTIONS

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

    def __post_init__(self) -> None:
        for name in self.__slots__:  # type: ignore[attr-defined]
            problem = _param_problem(name, getattr(self, name), self)
            if problem is not None:
                raise SignalError(f"signal parameter {name} {problem}, not {getattr(self, name)!r}")


#: the parameters the model divides by or takes the logarithm of: above 0
_POSITIVE: Final = frozenset({"tactile_rate", "peak_lo", "peak_hi", "creep_tau"})


def _param_problem(name: str, value: object, params: SignalParams) -> str | None:
    """What is wrong with one parameter of ``params`` (None if nothing): every number finite
    and not negative; a rate, a peak or a time constant above 0; ``slip_jerks`` a whole
    number from 1; a ``_p`` a probability; each range pair and ``_lo`` at most its ``_hi``."""
    numbers = value if isinstance(value, tuple) else (value,)
    if any(isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x) for x in numbers):
        return "must be a finite number" + (" pair (low, high)" if isinstance(value, tuple) else "")
    if any(x < 0 for x in numbers):  # type: ignore[operator]
        return "must be 0 or more"
    return _bound_problem(name, value, params)


def _bound_problem(name: str, value: object, params: SignalParams) -> str | None:
    """:func:`_param_problem` of a finite number (or pair) of 0 or more."""
    if name in _POSITIVE and value == 0:
        return "must be above 0 (the model divides by it or takes its logarithm)"
    if name == "slip_jerks" and (not isinstance(value, int) or value < 1):
        return "must be a whole number of jerks, 1 or more"
    if name.endswith("_p") and value > 1:  # type: ignore[operator]
        return "must be at most 1 (a probability)"
    if isinstance(value, tuple) and (len(value) != 2 or value[0] > value[1]):
        return "must be a range (low, high) with low at most high"
    if name.endswith("_lo") and value > getattr(params, name[:-3] + "_hi", math.inf):  # type: ignore[operator]
        return f"must be at most {name[:-3]}_hi, {getattr(params, name[:-3] + '_hi')!r} (the model draws between the two)"
    return None


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
    and, if requested, ``frames`` ``(K, 6, 14, 6)`` int16; ``flow``: the tactile flow of each
    frame worked out ahead (``desmon.detectors.tactile.FlowHint`` values) when a worker rendering
    ahead gave it for fault-free consecutive frames, else None."""

    index: Arr
    times: Arr
    moments: Arr
    frames: Arr | None = None
    flow: Arr | None = None


# --------------------------------------------------------------------------- shape helpers


def uniform(rng: np.random.Generator, lohi: tuple[float, float], size: int | tuple[int, ...]) -> Arr:
    """``rng.uniform(lo, hi, size)`` for a ``(lo, hi)`` parameter pair."""
    return rng.uniform(lohi[0], lohi[1], size)


def half_sine(t: Arr, t0: Arr, width: Arr) -> Arr:
    """``sin(pi (t - t0) / width)`` on ``[t0, t0 + width]``, zero elsewhere (broadcasting)."""
    u = (t - t0) / width
    return np.where((u >= 0.0) & (u <= 1.0), np.sin(np.pi * np.clip(u, 0.0, 1.0)), 0.0)


def jerky(t: Arr, t0: Arr, width: Arr, jerks: Arr | int) -> Arr:
    """Progress in ``jerks`` discrete steps: ``floor(N u) / N`` with ``u = clip((t - t0)/width, 0, 1)``."""
    u = np.clip((t - t0) / width, 0.0, 1.0)
    return np.floor(jerks * u) / jerks


# --------------------------------------------------------------------------- grids


def wrench_indices(t0: float, t1: float, rate: float) -> Arr:
    """Indices ``k`` of the fixed-rate wrench grid ``t = k / rate`` with ``t0 <= t < t1``."""
    k0 = max(0, math.floor(t0 * rate) - 1)
    k1 = max(k0, math.ceil(t1 * rate) + 1)
    # ``k / rate`` is non-decreasing in ``k`` (rounding is monotonic): the kept ones are one
    # run, from the first ``k`` of ``k0 .. k1 - 1`` with ``k / rate >= t0`` to the first with
    # ``k / rate >= t1``, each found by a few steps from its estimate (``k / rate`` in Python
    # is numpy's float64 division of the same numbers)
    return np.arange(_first_at(t0, rate, k0, k1, k0), _first_at(t1, rate, k0, k1, math.floor(t1 * rate) - 1), dtype=np.int64)


def _first_at(t: float, rate: float, k0: int, k1: int, guess: int) -> int:
    """The first ``k`` of ``k0 .. k1 - 1`` with ``k / rate >= t`` (``k1`` if none), from ``guess``."""
    k = min(max(guess, k0), k1)
    while k > k0 and (k - 1) / rate >= t:
        k -= 1
    while k < k1 and k / rate < t:
        k += 1
    return k


def tactile_nominal_indices(t0: float, t1: float, rate: float, slack: float) -> Arr:
    """Candidate frame numbers whose jittered time may fall in ``[t0, t1)`` (``slack`` = max |jitter|)."""
    return np.arange(*tactile_nominal_range(t0, t1, rate, slack), dtype=np.int64)


def tactile_nominal_range(t0: float, t1: float, rate: float, slack: float) -> tuple[int, int]:
    """:func:`tactile_nominal_indices` as the range ``(k0, k1)`` of those frame numbers."""
    k0 = max(0, math.floor((t0 - slack) * rate))
    return k0, max(k0, math.ceil((t1 + slack) * rate) + 1)


# --------------------------------------------------------------------------- checks


def no_signal_model(context: str) -> str:
    """The signal models exist for the built-in actions only; a model's own action is
    rendered as the built-in it is declared like (``desmon.sim.world.like_segments``)."""
    return (
        f"unknown context {context!r}: signal models exist for the built-in actions ({', '.join(ACTIONS)}); "
        "render a model's own action as the built-in it is like (SystemModel.like)"
    )


def check_contexts(segments: Sequence[Segment]) -> None:
    """Every segment has a built-in context, a positive finite duration, and starts at or after
    the previous one's end (and at t >= 0)."""
    prev_end = 0.0
    for i, s in enumerate(segments):
        if s.context not in ACTIONS:
            raise SignalError(f"segment {i}: {no_signal_model(s.context)}")
        if not (s.duration > 0 and math.isfinite(s.duration)):
            raise SignalError(f"segment {i} ({s.context}): duration {s.duration!r} must be a positive finite number")
        if s.start < prev_end - 1e-9 or s.start < 0:
            raise SignalError(
                f"segment {i} ({s.context}) starts at {s.start!r} before the previous one ends ({prev_end!r}); "
                "give segments in time order without overlap, starting at t >= 0"
            )
        prev_end = s.end


def check_faults(faults: Sequence[SensorFault]) -> tuple[SensorFault, ...]:
    """The faults, each with a known sensor and mode and ``end > start``."""
    for f in faults:
        if f.sensor not in ("wrench", "tactile") or f.mode not in ("silent", "stuck", "zero") or not f.end > f.start:
            raise SignalError(
                f"fault {f!r}: sensor must be 'wrench' or 'tactile', mode 'silent', 'stuck' or 'zero', end > start"
            )
    return tuple(faults)
