"""What ``desmon estimate`` can measure: a run's figures (the ones ``desmon sweep --job run``
writes), each with the range its values are known to lie in.

Seconds of the run (unmonitored exposure, its longest stretch, risky time, the exposure's
causes, blind time) lie in ``[0, horizon]``: the guaranteed interval of their mean needs nothing else.
Where the task plays out the same in every run (fixed timing), the exposure figures lie in
a narrower range the task fixes (:func:`natural_range`, :func:`task_seconds`).
Counts (switches, starts, slips missed, false alarms, errors by kind) have no bound
known in advance: their mean needs a declared range (``--range``), which every run's
value is then checked against; the probability that a count reaches a value
(``--at-least``) needs none. The detection latencies and the blind time per switch are
left out: a run that detects no slip has no latency, one with no switch no blind time per
switch, so their mean over runs is not defined.
"""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass
from typing import Any, Iterable, Mapping

from desmon.deployment.exposure import CAUSES
from desmon.deployment.ports import ERROR_KINDS
from desmon.errors import EstimateError
from desmon.sim.metrics import LONGEST_EXPOSURE, RUN_FIGURES, RUNTIME_CHANGES

__all__ = [
    "METRICS", "SECONDS", "LONGEST", "check_metric", "natural_range", "range_basis", "task_seconds", "TaskSeconds", "value_of", "longest_exposure",
    "DEFAULT_METRIC",
]

DEFAULT_METRIC = "exposure_s"
#: per-run statistics that a run may lack (no slip detected, no switch), each with what to
#: estimate instead: not estimable as a mean over runs
_UNDEFINED = {
    "latency_median_s": ("a run that detects no slip has no detection latency", "slips_missed or the probability of a late detection"),
    "latency_p95_s": ("a run that detects no slip has no detection latency", "slips_missed or the probability of a late detection"),
    "blind_time_per_switch_s": ("a run with no switch has no blind time per switch", "blind_time_max_s (0 in a run with no switch) or starting_s"),
}
#: the longest stretch of unmonitored exposure in a run (touching intervals joined): read from the
#: run itself, beyond desmon sweep's figures ("any 60 s unmonitored at once": --at-least 60)
LONGEST = LONGEST_EXPOSURE
#: every figure desmon estimate takes, in the order of desmon sweep's table
METRICS: tuple[str, ...] = (
    *(m for m in RUN_FIGURES if m not in _UNDEFINED), LONGEST, *(f"errors_{k}" for k in ERROR_KINDS), *RUNTIME_CHANGES,
)
#: the figures in seconds of simulated time: in [0, horizon] in every run (``leased_s``, summed
#: over the platforms leased at once, in [0, horizon x those platforms])
SECONDS: frozenset[str] = frozenset(m for m in METRICS if m.endswith("_s"))


def check_metric(name: str) -> str:
    """``name`` if desmon estimate takes it, else an EstimateError naming the valid ones (and the closest)."""
    if name in METRICS:
        return name
    if name in _UNDEFINED:
        why, instead = _UNDEFINED[name]
        raise EstimateError(
            f"--metric {name}: {why}, so its mean over runs is not defined; "
            f"estimate {instead} instead; the metrics are: {', '.join(METRICS)}"
        )
    close = difflib.get_close_matches(name, METRICS, n=1, cutoff=0.6)
    hint = f"did you mean {close[0]}? " if close else ""
    raise EstimateError(f"--metric {name!r}: no such run metric; {hint}choose one of {', '.join(METRICS)}")


@dataclass(frozen=True)
class TaskSeconds:
    """The seconds of a task that plays out the same in every run, up to the run's end: with
    an object in the hand (``risky``), of them in an action no rule covers (``no_rule``) and
    in one excluded on purpose (``excluded``), as the exposure meter counts them."""

    risky: float
    no_rule: float
    excluded: float


def task_seconds(scenario: Any, horizon: float) -> TaskSeconds | None:
    """:class:`TaskSeconds` of ``scenario``'s runs of ``horizon`` seconds where the World's
    timing is fixed (each step lasts its duration, so every seed plays the same steps at the
    same times), None where the steps vary with the seed. Each step's need lasts until the
    step ends (the next one begins then); after a task played once the hand is empty (the
    meter's rule)."""
    from desmon.deployment.exposure import needs_table
    from desmon.sim.world import expand_task, world_of

    world = world_of(scenario)
    if world.timing != "fixed":
        return None
    steps = expand_task(world, world.horizon)
    table = needs_table(scenario.model)
    risky = no_rule = excluded = 0.0
    for i, step in enumerate(steps):
        a = min(step.start, horizon)
        b = min(steps[i + 1].start if i + 1 < len(steps) else step.start + step.duration, horizon)
        need = table[step.context]
        if b <= a or not (need.counted or need.excluded):
            continue
        risky += b - a
        if need.excluded:
            excluded += b - a
        elif not need.slots:
            no_rule += b - a
    return TaskSeconds(risky, no_rule, excluded)


def natural_range(metric: str, horizon: float, scenario: Any = None) -> tuple[float, float] | None:
    """The range every run's ``metric`` lies in, known without running: ``[0, horizon]`` for
    seconds of the run, None for counts (a range must then be declared). Given the
    ``scenario``, a task that plays out the same in every run (:func:`task_seconds`) narrows
    the exposure figures to what it fixes: the exposure lies between the seconds no rule
    covers and the risky seconds not excluded, each of its other causes below their
    difference, the risky, no-rule and excluded seconds at their values (each end widened
    by :data:`ROUNDING_S` and :data:`TASK_SLACK` of the horizon for the meter's rounding)."""
    if metric not in SECONDS:
        return None
    if metric == "leased_s":  # summed over the platforms leased at once: each adds at most the horizon
        leasable = _leasable(scenario)
        return None if leasable is None else (0.0, float(horizon) * leasable)
    full = (0.0, float(horizon))
    fixed = task_seconds(scenario, horizon) if scenario is not None and metric in _TASK_BOUNDED else None
    if fixed is None:
        return full
    watched = fixed.risky - fixed.excluded
    lo, hi = {
        "exposure_s": (fixed.no_rule, watched),
        LONGEST: (0.0, watched),
        "risky_time_s": (fixed.risky, fixed.risky),
        "excluded_s": (fixed.excluded, fixed.excluded),
        "no_rule_s": (fixed.no_rule, fixed.no_rule),
    }.get(metric, (0.0, watched - fixed.no_rule))
    slack = ROUNDING_S + TASK_SLACK * float(horizon)
    return max(0.0, lo - slack), min(float(horizon), hi + slack)


def _leasable(scenario: Any) -> int | None:
    """How many platforms the World may lease at once (None without a scenario to ask): its
    lease's platforms, or every on-demand platform of the model; 0 without a lease."""
    if scenario is None:
        return None
    from desmon.sim.world import world_of

    lease = world_of(scenario).lease
    if lease is None:
        return 0
    return len(lease.platforms) if lease.platforms else sum(1 for p in scenario.model.platforms if p.on_demand)


def range_basis(metric: str, horizon: float, scenario: Any) -> str | None:
    """Why :func:`natural_range` gives ``metric`` a range narrower than ``[0, horizon]``
    (None where it does not): what the fixed task holds, for the report."""
    fixed = task_seconds(scenario, horizon) if metric in _TASK_BOUNDED else None
    if fixed is None:
        return None
    parts = [f"{fixed.risky:,.6g} s with an object in the hand"]
    if fixed.no_rule:
        parts.append(f"{fixed.no_rule:,.6g} s of them in actions no rule covers")
    if fixed.excluded:
        parts.append(f"{fixed.excluded:,.6g} s in actions excluded on purpose")
    return f"the task plays out the same in every run (fixed timing): {', '.join(parts)}"


#: how far a range from :func:`task_seconds` is widened at each end: the step a run's
#: figures in seconds are rounded to (``desmon.sim.accounting``), and a share of the horizon
#: for the meter's sums of many pieces
ROUNDING_S = 1e-6
TASK_SLACK = 1e-9
#: the figures a fixed task bounds more tightly than the horizon does (the exposure, its
#: causes and longest stretch, the risky and excluded seconds)
_TASK_BOUNDED = frozenset({"exposure_s", LONGEST, "risky_time_s", "excluded_s", *(f"{c}_s" for c in CAUSES)})


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
    the exposure went on) continues it. 0 without any. Rounded to :data:`ROUNDING_S`, as a
    run's other figures in seconds are (a stretch of 5.0 + 0.45 s is 5.45 s, not
    5.449999999999999, which ``--at-least 5.45`` would not count)."""
    longest, start, end = 0.0, None, None
    for a, b, _action in intervals:
        if start is None or end is None or a > end:
            start = a
        end = b
        longest = max(longest, end - start)
    return round(longest, 6)
