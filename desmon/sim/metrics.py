"""The metrics of docs/design.md §10, accumulated while the world runs.

* **Unmonitored exposure**: the definition of :mod:`desmon.deployment.exposure`, applied
  to the *true* action context: risky time (an object in the hand) in which a slot of
  what the selector's rule wants has no watching member (running on an up platform, its
  start latency and warm-up over, every input readable, able to detect here), or which
  no rule covers. The slots are kept apart: a covered slot (say the force detector in
  ``grasp``) does not hide an uncovered one (the tactile detector the same rule also
  wants). A graph whose inputs have no signal model (``World.no_signal_model``) cannot
  detect a slip: it runs and uses memory, but never counts as watching, signals on or
  off. :class:`Exposure` also splits the unmonitored seconds by cause
  (:data:`~desmon.deployment.exposure.CAUSES`), keeps the excluded seconds of actions
  declared ``watched=False``, and reports each interval it counts (for the trace's
  ``exposure`` start / end records).
* **Blind time per switch**: for every change of the true context that changes what
  the selector wants (a switch), the exposure between the change and the first moment
  every slot has a valid member (or the next switch).
* Slips injected / detected / missed (an alarm of a running detector in
  ``[t_s - 0.3, t_s + 1.0]``), detection latency (first such alarm - t_s), false alarms
  (alarms outside every slip window, debounced 0.5 s), errors by kind, per-platform
  memory peak and seconds over capacity. Both count background load + running
  detectors, unlike the ``no-overcommit`` invariant, which counts deployments only (the
  load is not a deployment): after the load rises the peak can pass the capacity for
  the instant (0 s) before the deployer reacts, and a deployer that leaves a detector
  on a loaded platform runs over capacity without violating ``no-overcommit``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from difflib import get_close_matches
from typing import Any, Callable, Iterable, Mapping

import numpy as np

from desmon.deployment.exposure import CAUSES, Needs
from desmon.deployment.ports import ERROR_KINDS
from desmon.detectors.base import Alarm, merge_alarms
from desmon.errors import SimulationError
from desmon.model.requirements import fits
from desmon.sim.world import Slip

__all__ = [
    "Exposure", "MemoryMeter", "slip_metrics", "percentile", "RUN_FIGURES", "RENAMED", "RUNTIME_CHANGES", "run_figures",
    "ALARM_FIGURES", "SIGNALS", "AUDIT", "RECORDS", "EVERY_ALARM", "work_read",
]

DETECT_BEFORE = 0.3
DETECT_AFTER = 1.0


class Exposure:
    """Integrates unmonitored exposure and blind time per switch over piecewise-constant state.

    ``slots`` are the selector's slots in the true context (each a set of alternative
    graphs, one of which must be valid; empty when not risky); ``valid_from(graph)``
    returns the earliest time from which a running instance of ``graph`` is valid
    (``inf`` if none). A moment is exposed when *any* slot has no valid member. State
    only changes at :meth:`advance` calls, but a warm-up ending between two calls is
    accounted exactly.

    Intervals: the owner calls :meth:`check` after every change of state (and at every
    warm-up end); each maximal interval of exposure in one true context is then
    reported to ``emit(t, "start" | "end", context)`` when it opens and closes, and
    kept in ``intervals``. Their lengths add up to ``exposure``.
    """

    def __init__(
        self, valid_from: Callable[[str], float], emit: Callable[[float, str, str], None] | None = None,
        valid_times: Callable[[], Mapping[str, float]] | None = None,
        cause_of: Callable[[Needs], str | None] | None = None,
    ) -> None:
        self.valid_from = valid_from
        #: the cause of an uncovered moment with no member about to be valid (the owner
        #: asks the definition with its members' states); None: ``not_deployed``
        self.cause_of = cause_of
        #: every graph's ``valid_from`` at once (graphs not in it: inf), if the owner can
        #: say so in one pass; else ``valid_from`` is asked graph by graph
        self.valid_times = valid_times
        self.emit = emit
        self.slots: tuple[frozenset[str], ...] = ()
        self.need: Needs | None = None
        #: unmonitored seconds by cause, and the seconds of actions declared watched=False
        self.by_cause: dict[str, float] = dict.fromkeys(CAUSES, 0.0)
        self.excluded = 0.0
        self.context = ""
        self.last = 0.0
        self.exposure = 0.0
        self.risky = 0.0
        self.switches = 0
        self.blind: list[float] = []
        self._open: int | None = None  # index into blind of the switch not yet covered
        self.open_since: float | None = None
        self.intervals: list[tuple[float, float, str]] = []
        self._wanted: dict[tuple, tuple[frozenset[str], ...]] = {}  # slots -> their sets (the rule table's few)

    def _covered_from(self, times: Mapping[str, float] | None = None) -> float:
        """The earliest time from which every slot has a valid member (``inf`` if never);
        ``times``: what ``valid_times()`` answers now, if the caller has it."""
        if self.valid_times is not None:
            # max over the slots of min over each slot's members, written out (the first
            # extreme wins, as with max() and min()): the meter asks at every change
            if times is None:
                times = self.valid_times()
            inf = math.inf
            get = times.get
            covered: float | None = None
            for slot in self.slots:
                best = inf
                for g in slot:
                    t = get(g, inf)
                    if t < best:
                        best = t
                if covered is None or best > covered:
                    covered = best
            if covered is None:
                raise ValueError("max() arg is an empty sequence")  # what max() says (no slot: the callers never ask)
            return covered
        vf = self.valid_from
        return max(min((vf(g) for g in slot), default=math.inf) for slot in self.slots)

    def advance(self, now: float, times: Mapping[str, float] | None = None) -> None:
        a, b = self.last, now
        need = self.need
        if b > a and need is not None and (need.counted or need.excluded):
            self.risky += b - a
            if need.excluded:
                self.excluded += b - a
            elif not self.slots:  # a risky action no rule covers: unmonitored throughout
                self.exposure += b - a
                self.by_cause["no_rule"] += b - a
            else:
                v = self._covered_from(times)
                start_cov = min(b, max(a, v))
                if start_cov > a:
                    self.exposure += start_cov - a
                    if v < math.inf:
                        why = "starting"  # a member becomes valid at v: its latency or warm-up runs
                    else:
                        why = (self.cause_of(need) if self.cause_of is not None else None) or "not_deployed"
                    self.by_cause[why] += start_cov - a
                if self._open is not None:
                    self.blind[self._open] += start_cov - a
                    if v <= b:
                        self._open = None
        self.last = max(self.last, now)

    def set_wanted(self, now: float, slots: Iterable[Iterable[str] | str], context: str = "") -> None:
        """The true context became ``context``, where the selector wants ``slots`` (as
        ``RuleTable.slots_for`` returns them; a bare graph name is a one-graph slot) and
        the context counts as risky exactly when it wants some: :meth:`set_need` with
        the definition's :class:`~desmon.deployment.exposure.Needs` is the full form."""
        try:  # the rule table's slots are tuples of tuples: their sets are made once
            wanted = self._wanted.get(slots)  # type: ignore[arg-type]
        except TypeError:  # slots given as lists
            wanted = None
        if wanted is None:
            wanted = tuple(frozenset((slot,) if isinstance(slot, str) else slot) for slot in slots)
            if type(slots) is tuple and all(type(slot) is tuple or type(slot) is str for slot in slots):
                self._wanted[slots] = wanted
        self.set_need(now, Needs(context, bool(wanted), False, wanted))

    def set_need(self, now: float, need: Needs) -> None:
        """The true context became ``need.action``, which the definition
        (:func:`desmon.deployment.exposure.needs`) asks ``need`` of."""
        wanted = need.slots
        # what valid_times() answers is the same for the advance and the check (nothing
        # between them changes an instance): asked once where both need it
        times = None
        if self.valid_times is not None and wanted and self.slots and now > self.last:
            times = self.valid_times()
        self.advance(now, times)
        context = need.action
        if context != self.context and self.open_since is not None:
            self._close(now)
        self.context = context
        self.need = need
        if wanted != self.slots:
            if wanted:
                self.switches += 1
                self.blind.append(0.0)
                self._open = len(self.blind) - 1
            else:
                self._open = None
            self.slots = wanted
        self.check(now, times)

    def check(self, now: float, times: Mapping[str, float] | None = None) -> None:
        """Open or close the exposure interval after a change of state at ``now``
        (``times``: what ``valid_times()`` answers now, if the caller has it)."""
        need = self.need
        exposed = need is not None and need.counted and (not self.slots or self._covered_from(times) > now)
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
        if not fits(prev, cap):
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


#: a run's figures, in table order, as ``desmon sweep`` and ``desmon estimate`` name them
#: (:func:`run_figures` adds ``errors_<kind>``, ``memory_peak_mb_<platform>`` and, where the
#: world has them, :data:`RUNTIME_CHANGES`)
RUN_FIGURES: tuple[str, ...] = (
    "exposure_s", "risky_time_s", "excluded_s", *(f"{c}_s" for c in CAUSES), "switches", "blind_time_per_switch_s", "blind_time_max_s",
    "starts", "start_failures", "stops", "migrations", "upgrades", "upgrades_failed", "errors", "slips_injected", "slips_detected",
    "slips_missed", "false_alarms", "latency_median_s", "latency_p95_s", "violations",
)
#: figures whose name differs from the run's metric
RENAMED = {"exposure_s": "unmonitored_exposure_s"}
#: run metrics present only when the world has run-time changes or a lease
RUNTIME_CHANGES = ("requirement_changes", "leases", "leased_s")
#: the longest stretch of unmonitored exposure in a run (its intervals' longest)
LONGEST_EXPOSURE = "longest_exposure_s"


def run_figures(m: Mapping[str, Any], violations: int) -> dict[str, Any]:
    """The figures of one run (:data:`RUN_FIGURES` and the per-kind, per-platform ones) from
    its ``metrics`` and its number of invariant violations."""
    row: dict[str, Any] = {k: m.get(RENAMED.get(k, k)) for k in RUN_FIGURES if k not in ("errors", "violations")}
    for c in CAUSES:  # the exposure's causes (desmon.deployment.exposure), beside the figure
        row[f"{c}_s"] = m["unmonitored_by_cause_s"][c]
    errors = dict(m.get("errors") or {})
    row["errors"] = sum(errors.values())
    row["violations"] = violations
    for kind, n in errors.items():
        row[f"errors_{kind}"] = n
    for platform, mb in (m.get("memory_peak_mb") or {}).items():
        row[f"memory_peak_mb_{platform}"] = mb
    for key in RUNTIME_CHANGES:  # only worlds with run-time changes or a lease report them
        if key in m:
            row[key] = m[key]
    return row


#: the figures read off the detectors' alarms: the only ones the signals and detectors
#: change (an alarm is recorded and counted, and nothing in the world reacts to it)
ALARM_FIGURES: frozenset[str] = frozenset({"slips_detected", "slips_missed", "false_alarms", "latency_median_s", "latency_p95_s"})
#: the work of a run that only some outputs read (:func:`work_read`): rendering the signals
#: and running the detectors on them, auditing the invariants, keeping the records (the
#: decisions, the trace's records), and running the detectors far from every slip
#: (``EVERY_ALARM``: only ``false_alarms`` counts the alarms there)
SIGNALS, AUDIT, RECORDS, EVERY_ALARM = "signals", "audit", "records", "every_alarm"
#: the names a caller may read of a run (``SimWorld(reads=...)``): the run figures, the
#: longest exposure, the errors per kind and the run-time changes
READABLE: frozenset[str] = frozenset(
    (*RUN_FIGURES, LONGEST_EXPOSURE, *(f"errors_{k}" for k in ERROR_KINDS), *RUNTIME_CHANGES)
)


def work_read(figures: frozenset[str] | None) -> frozenset[str]:
    """The work (:data:`SIGNALS`, :data:`AUDIT`, :data:`RECORDS`, :data:`EVERY_ALARM`) whose
    results a caller reading ``figures`` of a run sees (None: every output, so all of it).
    The alarms feed only :data:`ALARM_FIGURES`, and of those only ``false_alarms`` reads
    an alarm outside every slip's detection window; the audit feeds only ``violations``,
    the records no figure. Every other figure comes out the same without them."""
    if figures is None:
        return frozenset({SIGNALS, AUDIT, RECORDS, EVERY_ALARM})
    unknown = sorted(f for f in figures if f not in READABLE)
    if unknown:  # (a misspelt alarm figure would otherwise be read off a run without detectors: 0)
        close = get_close_matches(unknown[0], sorted(READABLE), n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise SimulationError(f"reads={unknown[0]!r} is no run figure{hint}: name figures of desmon.sim.metrics.READABLE")
    return frozenset(
        ({SIGNALS} if figures & ALARM_FIGURES else set()) | ({AUDIT} if "violations" in figures else set())
        | ({EVERY_ALARM} if "false_alarms" in figures else set())
    )
