"""``desmon estimate``: a figure of the simulated world with a guaranteed confidence interval,
from as many independent runs as the precision asked for needs (:mod:`desmon.estimate`).

Exit codes: 0 the interval is as narrow as asked (or the threshold question's answer is
yes), 1 the answer is no (or the value cannot be told apart from the threshold within
the indifference), 2 bad input (one line), 3 INCOMPLETE: ``--max-runs`` or ``--timeout``
came first (the interval of the runs made is printed all the same).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import time
from decimal import ROUND_CEILING, ROUND_FLOOR, Decimal
from typing import Any

from desmon.cli.common import EXIT_INCOMPLETE, EXIT_OK, EXIT_VIOLATED, Subparsers, deployer_arg, load_scenario_of, scenario_arg, world_given
from desmon.model.checks import exact
from desmon.cli.options import finite_number, non_negative_int, positive_seconds, run_count, worker_count

__all__ = ["add_parser", "run", "format_estimate", "parse_within", "parse_confidence", "percent"]


def parse_within(text: str) -> tuple[float, bool]:
    """``60`` -> (60.0, absolute); ``1%`` -> (0.01, relative): :func:`desmon.estimate.loop.parse_within` for argparse."""
    from desmon.errors import EstimateError
    from desmon.estimate.loop import parse_within as parse

    try:
        return parse(text)
    except EstimateError:
        try:
            float(text.strip().removesuffix("%"))
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be a half-width, absolute (60) or relative to the estimate (1%), got {text!r}") from None
        raise argparse.ArgumentTypeError(f"must be a positive half-width, absolute (60) or relative to the estimate (1%), got {text}") from None


def _fraction(text: str) -> float:
    """``text`` as a number, a percentage (``99%``) as its fraction; ValueError if it is neither."""
    t = text.strip()
    return float(t.removesuffix("%")) / (100.0 if t.endswith("%") else 1.0)


def parse_error_probability(text: str) -> float:
    """An error probability (``0.01``; ``1%`` too, as ``--confidence`` takes ``99%``); its
    bounds are the question's to check (:meth:`~desmon.estimate.Question.check`)."""
    try:
        v = _fraction(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be an error probability, e.g. 0.01 or 1%, got {text!r}") from None
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"must be a finite error probability, e.g. 0.01 or 1%, got {text}")
    return v


def parse_confidence(text: str) -> float:
    """A confidence strictly between 0 and 1 (``0.99``; ``99%`` too)."""
    try:
        v = _fraction(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a confidence between 0 and 1, e.g. 0.99, got {text!r}") from None
    if not (math.isfinite(v) and 0.0 < v < 1.0):
        read = f" (read as {v:g}: more digits than a double holds)" if v in (0.0, 1.0) and text.strip().rstrip("%") not in ("0", "1", "100") else ""
        raise argparse.ArgumentTypeError(f"must be a confidence strictly between 0 and 1, e.g. 0.99, got {text}{read}")
    return v


def add_parser(sub: Subparsers) -> None:
    p = sub.add_parser("estimate", help="a run figure's mean (or probability) with a guaranteed confidence interval, from as many runs as needed")
    scenario_arg(p)
    deployer_arg(p)
    p.add_argument("--metric", default="exposure_s", help="the run figure, as desmon sweep names it: exposure_s, risky_time_s, "
                   "slips_missed, false_alarms, errors_<kind>, ..., or longest_exposure_s (a wrong name lists them all)")
    p.add_argument("--within", type=parse_within, default="5%", metavar="EPS",
                   help="stop once the guaranteed interval's half-width is at most EPS: absolute (60) or relative to the estimate (1%%); "
                   "with --below, the indifference around the threshold")
    p.add_argument("--confidence", type=parse_confidence, default=None, metavar="1-DELTA", help="the interval's confidence, e.g. 0.99 (unset: 0.95)")
    p.add_argument("--at-least", type=finite_number, default=None, metavar="X",
                   help="estimate the probability that the figure is X or more in a run, not its mean (--metric longest_exposure_s "
                   "--at-least 60: 60 s or more unmonitored at a stretch)")
    p.add_argument("--below", type=finite_number, default=None, metavar="X",
                   help="answer yes or no: is the mean (with --at-least: the probability) below X? Wald's test for a probability")
    p.add_argument("--alpha", type=parse_error_probability, default=None, help="--below: the chance of a wrong yes (unset: 1 - confidence)")
    p.add_argument("--beta", type=parse_error_probability, default=None, help="--below with --at-least: the chance of a wrong no (unset: 1 - confidence)")
    p.add_argument("--range", type=finite_number, nargs=2, default=None, metavar=("LOW", "HIGH"),
                   help="the range every run's value lies in (seconds: [0, horizon] unless given, narrower where fixed timing fixes the task's seconds; a count's mean needs one)")
    p.add_argument("--max-runs", type=run_count, default=10_000, metavar="N", help="stop INCOMPLETE (exit 3) after N runs")
    p.add_argument("--timeout", type=positive_seconds, default=None, metavar="S", help="stop INCOMPLETE (exit 3) after S wall seconds (unset: no limit)")
    p.add_argument("--seed", type=non_negative_int, default=0, help="the seed every run's seed is derived from")
    p.add_argument("--until", type=positive_seconds, default=None, help="simulated seconds per run (unset: the scenario's horizon)")
    p.add_argument("--timing", choices=("fixed", "exponential"), default=None,
                   help="exponential: the Markov world desmon analyze solves (random step durations with the given means)")
    p.add_argument("--no-signals", action="store_true", help="simulate no sensor signals (exposure counts running, ready detectors)")
    p.add_argument("--workers", type=worker_count, default=None, metavar="N",
                   help="run in batches on a local Dask cluster of N worker processes (unset: in this process); the output is the same")
    p.add_argument("--scheduler", default=None, metavar="tcp://HOST:PORT", help="run in batches on this existing Dask cluster")
    p.add_argument("--json", action="store_true", help="print the estimate as JSON")
    p.add_argument("--no-progress", action="store_true", help="no progress line on stderr")
    p.set_defaults(handler=run)


def _question(args: argparse.Namespace) -> Any:
    from desmon.errors import EstimateError
    from desmon.estimate import Question
    from desmon.estimate.measures import check_metric

    within, relative = args.within
    if args.confidence is not None and args.alpha is not None and args.below is not None and args.at_least is None:
        raise EstimateError(
            f"--confidence {args.confidence:.10g} and --alpha {args.alpha:.10g} both set the confidence of a mean's threshold test, "
            "whose interval is at 1 - alpha: give one of them"
        )
    q = Question(
        metric=check_metric(args.metric), within=within, relative=relative,
        confidence=0.95 if args.confidence is None else args.confidence, at_least=args.at_least,
        below=args.below, alpha=args.alpha, beta=args.beta, range=tuple(args.range) if args.range else None,
        max_runs=args.max_runs, timeout=args.timeout,
    )
    q.check()
    return q


def _world_changes(args: argparse.Namespace) -> dict[str, Any]:
    changes: dict[str, Any] = {}
    if args.timing is not None:
        changes["timing"] = args.timing
    if args.no_signals:
        changes["signals"] = False
    return changes


def _dask_source(args: argparse.Namespace, question: Any) -> Any:
    """The runs' values computed on Dask (``--workers``, ``--scheduler``), or None: in this process."""
    if args.workers is None and args.scheduler is None:
        return None
    import os

    from desmon.errors import EstimateError
    from desmon.model.params import parse_assignments
    from desmon.sweep.estimate import BatchSpec, dask_values
    from desmon.sweep.runner import check_scheduler_address, probe_scheduler, require_extra

    require_extra("estimate --workers", ("distributed",))
    if args.scheduler is not None:
        check_scheduler_address(args.scheduler)
        if args.workers is not None:
            raise EstimateError("--workers sets the size of the local cluster; with --scheduler the cluster has its own workers: drop it")
        probe_scheduler(args.scheduler)
    params = tuple(sorted(parse_assignments(args.param).items()))
    spec = BatchSpec(
        os.path.abspath(args.scenario), params, getattr(args.deployer, "name", str(args.deployer)), args.seed, args.until,
        question.metric, tuple(sorted(_world_changes(args).items())), max_commands=getattr(args, "max_commands", None),
        max_reaction_seconds=getattr(args, "max_reaction_seconds", None),
    )
    deadline = None if question.timeout is None else time.monotonic() + question.timeout
    return dask_values(spec, scheduler=args.scheduler, workers=args.workers, deadline=deadline)


def run(args: argparse.Namespace) -> int:
    from desmon.estimate import estimate
    from desmon.estimate.loop import with_world
    from desmon.progress import StatusLine
    from desmon.stats import decimals_for

    question = _question(args)
    scenario = with_world(load_scenario_of(args), _world_changes(args))
    show = not args.no_progress and not args.json and sys.stderr.isatty()
    line = StatusLine(sys.stderr)

    def progress(tracker: Any) -> None:
        n, iv = len(tracker.values), tracker.last
        if show and (n <= 10 or n % 10 == 0):
            now = ""
            if iv is not None:
                goal = f" (goal {_n(question.half_width_goal(iv.estimate))})" if question.below is None else ""
                d = decimals_for(iv.half_width)
                now = f", {_fixed(iv.estimate, d)} in [{_end(iv.low, d, False)}, {_end(iv.high, d, True)}], half-width {_fixed(iv.half_width, d)}{goal} at run {iv.n:,}"
            line.show(f"desmon estimate: {n:,} runs{now}")

    try:
        result = estimate(
            scenario, question, deployer=args.deployer, seed=args.seed, until=args.until, values=_dask_source(args, question),
            progress=progress, guard=args.guard,
        )
    finally:
        line.close()
    result = dataclasses.replace(result, world=world_given(args))
    if args.json:
        sys.stdout.write(json.dumps(result.to_json(), indent=2, allow_nan=False) + "\n")
    else:
        sys.stdout.write(format_estimate(result))
    if not result.complete:
        if result.status == "max-runs":
            why = f"--max-runs {question.max_runs} reached"
        elif result.status == "timeout":
            why = f"--timeout {question.timeout:g} s passed"
        else:
            why = "the runs' values ran out"
        zero = ""
        if question.relative and question.below is None and result.interval.estimate == 0:  # its goal: a half-width of 0
            zero = (f"; --within {question.within * 100:g}% of an estimate of 0 is a half-width of 0, which no number of runs reaches: "
                    f"give an absolute half-width, e.g. --within {_n(result.interval.half_width / 2)}")
        print(f"desmon estimate: INCOMPLETE: {why} before the question was answered; the interval above is that of the {result.runs:,} runs made{zero}",
              file=sys.stderr)
        return EXIT_INCOMPLETE
    return EXIT_VIOLATED if result.answer in ("no", "indifferent") else EXIT_OK


def _n(x: float) -> str:
    if not math.isfinite(x):
        return "-"
    return f"{x:,.0f}" if abs(x) >= 1000 else f"{x:,.4g}"


def _fixed(x: float, decimals: int) -> str:
    """``x`` with ``decimals`` decimals and thousands separators (``-`` if not finite; no ``-0.0``)."""
    if not math.isfinite(x):
        return "-"
    return f"{round(x, decimals) + 0.0:,.{decimals}f}"


def _outward(x: float, decimals: int, up: bool) -> Decimal | None:
    """``x`` to ``decimals`` decimals, rounded up (``up``) or down: a guaranteed interval's ends
    are printed outward, so the interval printed holds the one computed (None if not finite)."""
    if not math.isfinite(x):
        return None
    q = Decimal(x).quantize(Decimal(1).scaleb(-decimals), rounding=ROUND_CEILING if up else ROUND_FLOOR)
    return abs(q) if q == 0 else q  # (no -0.00)


def _end(x: float, decimals: int, up: bool) -> str:
    """An interval's end as :func:`_fixed` prints a number, rounded outward (:func:`_outward`)."""
    q = _outward(x, decimals, up)
    return "-" if q is None else f"{q:,.{decimals}f}"


def _range_ends(value_range: tuple[float, float], interval: tuple[float, float], decimals: int) -> list[str]:
    """The ends of the range every run's value is assumed in, as the report prints them: to
    four significant digits; every digit where that shows one number twice ([32.1, 32.1]);
    rounded outward with the interval's ``decimals`` where an end of the interval, itself
    rounded outward, would otherwise print beyond them (the range's ends carry the meter's
    rounding slack: an interval [8, 112] inside a range of [8.999998, 111.000002] is
    printed inside [8, 112], not [9, 111])."""
    ends = [_n(x) for x in value_range]
    if len(set(ends)) == 1:
        return [exact(x) for x in value_range]
    low, high = _outward(interval[0], decimals, False), _outward(interval[1], decimals, True)
    shown = [Decimal(x.replace(",", "")) for x in ends]
    if (low is not None and low < shown[0]) or (high is not None and high > shown[1]):
        return [_end(value_range[0], decimals, False), _end(value_range[1], decimals, True)]
    return ends


def _apart(decimals: int, ends: tuple[float, float], threshold: float) -> int:
    """``decimals``, or more where fewer would print an end (rounded outward) on the other side
    of ``threshold`` (or on it): an interval that answers "below X?" never reads as reaching X
    when it does not."""
    def crosses(x: float, up: bool) -> bool:
        q = _outward(x, decimals, up)
        return q is not None and (q < Decimal(threshold)) != (x < threshold)

    while decimals < 17 and (crosses(ends[0], False) or crosses(ends[1], True)):
        decimals += 1
    return decimals


def percent(confidence: float) -> str:
    """``confidence`` in percent, with every digit it needs: 0.9999999 is not 100 %, nor is
    0.9999999999999999."""
    pct = 100.0 * confidence
    short = f"{pct:.10g}"
    if float(short) != pct and (float(short) >= 100.0) != (confidence >= 1.0):
        return repr(pct)
    return short


def format_estimate(e: Any) -> str:
    """The text report of ``desmon estimate``: the estimate, both intervals' ends, the half-width
    and (for a mean) the values' extremes all with the decimals the guaranteed interval's
    half-width calls for (:func:`desmon.stats.decimals_for`)."""
    from desmon.stats import decimals_for

    q, iv, ap = e.question, e.interval, e.approximation
    d = decimals_for(iv.half_width)
    if q.below is not None and q.kind != "probability":  # each end printed on its own side of the threshold
        d = _apart(d, (iv.low, iv.high), q.below)
    f = lambda x: _fixed(x, d)  # noqa: E731
    pct = f"{percent(q.interval_confidence)} %"
    what = f"P({q.metric} >= {exact(q.at_least)}) per run" if q.kind == "probability" else f"mean {q.metric} per run"
    out = [f"desmon estimate: {e.scenario} (deployer {e.deployer}), {what} of {_n(e.horizon)} s simulated, seed {e.seed}"]
    if e.world:
        out.append(f"  world: the scenario's, with {' '.join(e.world)}")
    share = 100 * iv.half_width / abs(iv.estimate) if iv.estimate else math.nan
    rel = f" = {share:.2f} % of the estimate" if math.isfinite(share) else ""
    out.append(f"  estimate {f(iv.estimate)}, {pct} interval [{_end(iv.low, d, False)}, {_end(iv.high, d, True)}] "
               f"(half-width {f(iv.half_width)}{rel}), guaranteed")
    ends = _range_ends(e.range, (iv.low, iv.high), d) if e.range else []
    out.append(f"    method: {iv.method}" + (f"; every run's value assumed in [{ends[0]}, {ends[1]}]" if e.range else ""))
    if e.range_basis:
        out.append(f"    range: {e.range_basis}")
    out.append(f"  {ap.method}: [{f(ap.low)}, {f(ap.high)}]")
    v = _n if q.kind == "probability" else f  # a probability's runs give values of another figure (seconds, counts)
    out.append(f"  runs: {e.runs:,} (seeds derived from --seed {e.seed}); values {v(e.low_value)} .. {v(e.high_value)}")
    if q.below is not None:
        out.append(_answer_line(e))
    elif e.complete:
        goal = f"{100 * q.within:g} % of the estimate" if q.relative else f"{q.within:g}"
        out.append(f"  stopped: the half-width reached {goal}")
    return "\n".join(out) + "\n"


def _answer_line(e: Any) -> str:
    q = e.question
    subject = f"P({q.metric} >= {exact(q.at_least)})" if q.kind == "probability" else f"the mean {q.metric}"
    eps = q.indifference()
    if e.answer is None:
        return f"  below {exact(q.below)}? not decided ({e.test_method})"
    if q.kind == "probability":
        a = q.alpha if q.alpha is not None else q.delta
        b = q.beta if q.beta is not None else q.delta
        errors = f"a wrong yes at most {a:g} if it is {q.below + eps:g} or more, a wrong no at most {b:g} if it is {q.below - eps:g} or less"
    else:
        a = q.alpha if q.alpha is not None else q.delta
        errors = f"wrong with probability at most {a:g}"
    below = exact(q.below)
    words = {"yes": f"YES, {subject} is below {below}", "no": f"NO, {subject} is not below {below}",
             "indifferent": f"CANNOT TELL: {subject} is within +-{eps:g} of {below}"}
    return f"  below {below}? {words[e.answer]} ({e.test_method}: {errors})"
