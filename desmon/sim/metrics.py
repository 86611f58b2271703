"""The metrics of DESIGN.md §6, accumulated while the world runs.

* **Unmonitored exposure**: seconds in which the robot's *true* action context is one
  for which the selector wants a detector, and no instance of a selected graph is
  running on an up platform with its inputs and warmed up.
  :class:`Exposure` also reports each interval it counts (for the trace's
  ``exposure`` start / end records).
* **Blind time per switch**: for every change of the true context that changes what
  the selector wants (a switch), the exposure between the change and the first moment
  a selected detector is valid (or the next switch).
* Slips injected / detected / missed (an alarm of a running detector in
  ``[t_s - 0.3, t_s + 1.0]``), detection latency (first such alarm - t_s), false alarms
  (alarms outside every slip window, debounced 0.5 s), errors by kind, per-platform
  memory peak and seconds over capacity.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable, Mapping

import numpy as np

from desmon.detectors.base import Alarm, merge_alarms
from desmon.sim.world import Slip

__all__ = ["Exposure", "MemoryMeter", "slip_metrics", "percentile"]

DETECT_BEFORE = 0.3
DETECT_AFTER = 1.0


class Exposure:
    """Integrates unmonitored exposure and blind time per switch over piecewise-constant state.

    ``wanted`` is the set of graphs the selector wants in the true context (empty when
    not risky); ``valid_from(graph)`` returns the earliest time from which a running
    instance of ``graph`` is valid (``inf`` if none). State only changes at
    :meth:`advance` calls, but a warm-up ending between two calls is accounted exactly.

    Intervals: the owner calls :meth:`check` after every change of state (and at every
    warm-up end); each maximal interval of exposure in one true context is then
    reported to ``emit(t, "start" | "end", context)`` when it opens and closes, and
    kept in ``intervals``. Their lengths add up to ``exposure``.
    """

    def __init__(self, valid_from: Callable[[str], float], emit: Callable[[float, str, str], None] | None = None) -> None:
        self.valid_from = valid_from
        self.emit = emit
        self.wanted: frozenset[str] = frozenset()
        self.context = ""
        self.last = 0.0
        self.exposure = 0.0
        self.risky = 0.0
        self.switches = 0
        self.blind: list[float] = []
        self._open: int | None = None  # index into blind of the switch not yet covered
        self.open_since: float | None = None
        self.intervals: list[tuple[float, float, str]] = []

    def _vmin(self) -> float:
        return min((self.valid_from(g) for g in self.wanted), default=math.inf)

    def advance(self, now: float) -> None:
        a, b = self.last, now
        if b > a and self.wanted:
            v = self._vmin()
            start_cov = min(b, max(a, v))
            self.exposure += start_cov - a
            self.risky += b - a
            if self._open is not None:
                self.blind[self._open] += start_cov - a
                if v <= b:
                    self._open = None
        self.last = max(self.last, now)

    def set_wanted(self, now: float, wanted: frozenset[str], context: str = "") -> None:
        self.advance(now)
        if context != self.context and self.open_since is not None:
            self._close(now)
        self.context = context
        if wanted != self.wanted:
            if wanted:
                self.switches += 1
                self.blind.append(0.0)
                self._open = len(self.blind) - 1
            else:
                self._open = None
            self.wanted = wanted
        self.check(now)

    def check(self, now: float) -> None:
        """Open or close the exposure interval after a change of state at ``now``."""
        exposed = bool(self.wanted) and self._vmin() > now
        if exposed and self.open_since is None:
            self.open_since = now
            if self.emit is not None:
                self.emit(now, "start", self.context)
        elif not exposed and self.open_since is not None:
            self._close(now)

    def _close(self, now: float) -> None:
        assert self.open_since is not None
        self.intervals.append((self.open_since, now, self.context))
        self.open_since = None
        if self.emit is not None:
            self.emit(now, "end", self.context)

    def close(self, now: float) -> None:
        """End of the run: account up to ``now`` and close an open interval there."""
        self.advance(now)
        if self.open_since is not None:
            self._close(now)


@dataclass
class MemoryMeter:
    """Per-platform memory in use (background load + running detectors) over time."""

    capacity: Mapping[str, float]
    used: dict[str, float] = field(default_factory=dict)
    peak: dict[str, float] = field(default_factory=dict)
    over: dict[str, float] = field(default_factory=dict)
    last: dict[str, float] = field(default_factory=dict)

    def set(self, platform: str, now: float, amount: float) -> None:
        prev = self.used.get(platform, 0.0)
        since = self.last.get(platform, 0.0)
        cap = self.capacity.get(platform, math.inf)
        if prev > cap:
            self.over[platform] = self.over.get(platform, 0.0) + (now - since)
        self.used[platform] = amount
        self.last[platform] = now
        self.peak[platform] = max(self.peak.get(platform, 0.0), amount)

    def close(self, now: float) -> None:
        for p, amount in list(self.used.items()):
            self.set(p, now, amount)


def percentile(xs: Iterable[float], q: float) -> float | None:
    arr = np.asarray(list(xs), dtype=float)
    if arr.size == 0:
        return None
    return float(np.percentile(arr, q, method="linear"))


def slip_metrics(slips: Iterable[Slip], alarms: Iterable[Alarm]) -> dict[str, Any]:
    """Detected / missed slips, latency and false alarms from the slips and all alarms."""
    slips = list(slips)
    times = np.sort(np.array([a.time for a in alarms], dtype=float))
    detected, latencies = 0, []
    in_window = np.zeros(times.shape, dtype=bool)
    for s in slips:
        lo, hi = s.time - DETECT_BEFORE, s.time + DETECT_AFTER
        i0, i1 = np.searchsorted(times, lo, "left"), np.searchsorted(times, hi, "right")
        in_window[i0:i1] = True
        if i1 > i0:
            detected += 1
            latencies.append(float(times[i0]) - s.time)
    outside = [Alarm(float(t), "", None) for t in times[~in_window]]
    false_alarms = len(merge_alarms(outside, 0.5))
    return {
        "slips_injected": len(slips),
        "slips_detected": detected,
        "slips_missed": len(slips) - detected,
        "false_alarms": false_alarms,
        "latency_median_s": _r(percentile(latencies, 50)),
        "latency_p95_s": _r(percentile(latencies, 95)),
        "latencies": [round(x, 6) for x in latencies],
    }


def _r(x: float | None) -> float | None:
    return None if x is None else round(x, 6)
