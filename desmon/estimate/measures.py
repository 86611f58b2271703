"""What ``desmon estimate`` can measure: a run's figures (the ones ``desmon sweep --job run``
writes), each with the range its values are known to lie in.

Seconds of the run (unmonitored exposure, its longest stretch, risky time, the exposure's
causes, blind time) lie in ``[0, horizon]``: the guaranteed interval of their mean needs nothing else.
Counts (switches, starts, slips missed, false alarms, errors by kind) have no bound
known in advance: their mean needs a declared range (``--range``), which every run's
value is then checked against; the probability that a count reaches a value
(``--at-least``) needs none. The detection latencies are left out: a run that detects
no slip has none, so their mean over runs is not defined.
"""

from __future__ import annotations

import difflib
import math
from typing import Any, Iterable, Mapping

from desmon.deployment.ports import ERROR_KINDS
from desmon.errors import EstimateError
from desmon.sim.metrics import LONGEST_EXPOSURE, RUN_FIGURES, RUNTIME_CHANGES

__all__ = ["METRICS", "SECONDS", "LONGEST", "check_metric", "natural_range", "value_of", "longest_exposure", "DEFAULT_METRIC"]

DEFAULT_METRIC = "exposure_s"
#: per-run statistics that a run may lack (no slip detected): not estimable as a mean over runs
_UNDEFINED = ("latency_median_s", "latency_p95_s")
#: the longest stretch of unmonitored exposure in a run (touching intervals joined): read from the
#: run itself, beyond desmon sweep's figures ("any 60 s unmonitored at once": --at-least 60)
LONGEST = LONGEST_EXPOSURE
#: every figure desmon estimate takes, in the order of desmon sweep's table
METRICS: tuple[str, ...] = (
    *(m for m in RUN_FIGURES if m not in _UNDEFINED), LONGEST, *(f"errors_{k}" for k in ERROR_KINDS), *RUNTIME_CHANGES,
)
#: the figures in seconds of simulated time: in [0, horizon] in every run
SECONDS: frozenset[str] = frozenset(m for m in METRICS if m.endswith("_s"))


def check_metric(name: str) -> str:
    """``name`` if desmon estimate takes it, else an EstimateError naming the valid ones (and the closest)."""
    if name in METRICS:
        return name
    if name in _UNDEFINED:
        raise EstimateError(
            f"--metric {name}: a run that detects no slip has no detection latency, so its mean over runs is not defined; "
            f"estimate slips_missed or the probability of a late detection instead; the metrics are: {', '.join(METRICS)}"
        )
    close = difflib.get_close_matches(name, METRICS, n=1, cutoff=0.6)
    hint = f"did you mean {close[0]}? " if close else ""
    raise EstimateError(f"--metric {name!r}: no such run metric; {hint}choose one of {', '.join(METRICS)}")


def natural_range(metric: str, horizon: float) -> tuple[float, float] | None:
    """The range every run's ``metric`` lies in, known without running: ``[0, horizon]`` for
    seconds of the run, None for counts (a range must then be declared)."""
    return (0.0, float(horizon)) if metric in SECONDS else None


def value_of(figures: Mapping[str, Any], metric: str) -> float:
    """The run's ``metric`` from its figures (:func:`desmon.sim.metrics.run_figures`); an
    error kind or run-time change the run did not have counts 0."""
    v = figures.get(metric)
    if v is None and (metric.startswith("errors_") or metric in RUNTIME_CHANGES):
        return 0.0
    if v is None or isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise EstimateError(f"--metric {metric}: a run gave no number for it ({v!r}); choose another metric")
    return float(v)


def longest_exposure(intervals: Iterable[tuple[float, float, str]]) -> float:
    """The longest unmonitored stretch of a run, from its exposure intervals (start, end, action)
    in time order: an interval that starts where the previous one ended (the action changed,
    the exposure went on) continues it. 0 without any."""
    longest, start, end = 0.0, None, None
    for a, b, _action in intervals:
        if start is None or end is None or a > end:
            start = a
        end = b
        longest = max(longest, end - start)
    return longest
