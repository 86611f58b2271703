"""Shared detector vocabulary: alarm records, detector status, alarm debouncing."""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import StrEnum
from typing import ClassVar, Final, Sequence

import numpy as np

from desmon.errors import SignalError

__all__ = ["Alarm", "DetectorState", "DetectorStatus", "StreamingDetector", "merge_alarms", "check_threshold"]


@dataclass(frozen=True, slots=True)
class Alarm:
    """A detector output: at ``time`` (s) ``detector`` reports a slip; ``direction`` is
    ``'up'``, ``'down'`` or ``None`` (the tactile detector has no direction)."""

    time: float
    detector: str
    direction: str | None


class DetectorState(StrEnum):
    """Whether a detector's silence means "no slip".

    Only ``OK`` does. ``WARMING`` (tare / warm-up after activation) and ``NO_INPUT``
    (no samples, stuck or all-zero sensor output) mean the detector is blind.
    """

    INACTIVE = "inactive"
    WARMING = "warming"
    OK = "ok"
    NO_INPUT = "no_input"


@dataclass(frozen=True, slots=True)
class DetectorStatus:
    """State of a detector since ``since`` (s); ``reason`` explains WARMING / NO_INPUT
    (``'tare'``, ``'warm_up'``, ``'no_samples'``, ``'stuck'``, ``'no_contact'``)."""

    state: DetectorState
    reason: str = ""
    since: float = 0.0

    @property
    def valid(self) -> bool:
        """True when the detector has valid, warmed-up input (its silence means no slip)."""
        return self.state is DetectorState.OK


INACTIVE_STATUS: Final = DetectorStatus(DetectorState.INACTIVE, "", 0.0)


class StreamingDetector:
    """Activation and status bookkeeping shared by the streaming force and tactile detectors.

    A subclass sets ``_active`` / ``status`` in its ``__init__``, implements
    :meth:`_reset` (forget the per-activation history) and names the reason of its
    WARMING status after activation in ``WARMUP_REASON``.
    """

    #: the WARMING reason right after :meth:`activate`
    WARMUP_REASON: ClassVar[str] = "warm_up"
    _active: bool
    status: DetectorStatus

    def _reset(self, t: float) -> None:
        raise NotImplementedError

    @property
    def active(self) -> bool:
        return self._active

    def activate(self, t: float) -> None:
        """Start (or restart) at time ``t``: forget the history and warm up again (the
        force detector re-takes its tare, the tactile one restarts its flow history)."""
        self._active = True
        self._reset(float(t))
        self._set(DetectorState.WARMING, self.WARMUP_REASON, float(t))

    def deactivate(self) -> None:
        self._active = False
        self.status = INACTIVE_STATUS

    def _set(self, state: DetectorState, reason: str, t: float) -> None:
        """Change the status; ``since`` moves only when the state or reason changes."""
        if self.status.state is not state or self.status.reason != reason:
            self.status = DetectorStatus(state, reason, t)


def check_threshold(name: str, value: float) -> float:
    """Validate a positive finite threshold/duration parameter."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise SignalError(f"{name} {value!r} must be a number")
    v = float(value)
    if not (v > 0 and math.isfinite(v)):
        raise SignalError(f"{name} {value!r} must be a positive finite number")
    return v


def merge_alarms(alarms: Sequence[Alarm], gap: float = 0.5) -> tuple[Alarm, ...]:
    """Debounce: keep the first alarm of every run whose successive alarms are < ``gap`` s apart."""
    out: list[Alarm] = []
    last = -math.inf
    for a in sorted(alarms, key=lambda x: x.time):
        if a.time - last >= gap or not out:
            out.append(a)
        last = a.time
    return tuple(out)
