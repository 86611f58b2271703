"""The estimation loop: independent runs of the SimPy world, one seed each, until the
guaranteed interval is as narrow as asked (or a yes/no answer is reached), the run
budget is spent or the time is up.

Run ``i`` (counted from 0) of an estimation with seed ``s`` runs the world with the seed
:func:`run_seed` ``(s, i)``, or, should an earlier run have drawn that 32-bit seed already,
the next draw no run took (:class:`RunSeeds`: no run is repeated); the runs' values are
taken in that order, whoever computed
them (this process, or Dask workers in batches: :mod:`desmon.sweep.estimate`), and the
stopping rule is applied at fixed looks (:func:`is_look`), so an estimation's output
depends on its seed and its question only, not on the number of workers.
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass
from typing import Any, Callable, Iterable, Iterator

from desmon.errors import EstimateError
from desmon.estimate.measures import (
    DEFAULT_METRIC, LONGEST, ROUNDING_S, TASK_SLACK, check_metric, longest_exposure, natural_range, range_basis, value_of,
)
from desmon.model.checks import check_number
from desmon.stats import BettingSequence, Interval, ProportionSequence, WaldTest, clopper_pearson, normal_interval

__all__ = ["Question", "Estimate", "estimate", "run_seed", "RunSeeds", "run_value", "serial_values", "is_look", "world_horizon", "Tracker", "with_world", "parse_within"]

#: ``status`` of an estimation: done as asked, or INCOMPLETE (exit 3) at the run budget or the time
#: limit, or where the ``values`` given to :func:`estimate` ran out first (the Python API)
PRECISE, DECIDED, MAX_RUNS, TIMEOUT, VALUES_ENDED = "precise", "decided", "max-runs", "timeout", "values-ended"
#: runs up to which the stopping rule looks after every run; past it, every n // LOOKS_DENSE runs
LOOKS_DENSE = 64


#: a word of every run's seed sequence, so an estimation's streams are its own
_ESTIMATE_TAG = 0x65737469


def run_seed(seed: int, index: int) -> int:
    """The first world seed drawn for run ``index`` of an estimation with ``seed`` (an
    independent stream per run; :class:`RunSeeds` gives the one the run takes)."""
    import numpy as np

    return int(np.random.SeedSequence([int(seed), int(index), _ESTIMATE_TAG]).generate_state(1)[0])


class RunSeeds:
    """The world seeds of an estimation's runs in index order, each one distinct: run ``i``
    takes :func:`run_seed` ``(s, i)``, or, where an earlier run took that seed already, the
    next 32-bit draw of run ``i``'s own sequence that none took. Two of 10,000 draws of 32
    bits coincide with chance about 1 %, and a repeated seed repeats a whole run, which
    independent runs must not do. Computed once, in order, by whoever hands the runs out."""

    def __init__(self, seed: int) -> None:
        self.seed = int(seed)
        self._seeds: list[int] = []
        self._taken: set[int] = set()

    def batch(self, start: int, count: int) -> list[int]:
        """The seeds of runs ``start`` .. ``start + count - 1``."""
        import numpy as np

        while len(self._seeds) < start + count:
            draws = np.random.SeedSequence([self.seed, len(self._seeds), _ESTIMATE_TAG])
            k = 1
            s = int(draws.generate_state(1)[0])
            while s in self._taken:  # (the first draws of generate_state(k) are those of a shorter k)
                k += 1
                s = int(draws.generate_state(k)[k - 1])
            self._taken.add(s)
            self._seeds.append(s)
        return self._seeds[start:start + count]


def parse_within(text: str) -> tuple[float, bool]:
    """``--within``: ``"60"`` -> (60.0, absolute); ``"1%"`` -> (0.01, relative to the estimate); else an EstimateError."""
    t = str(text).strip()
    relative = t.endswith("%")
    try:
        v = float(t.removesuffix("%"))
    except ValueError:
        raise EstimateError(f"--within {text!r}: give a half-width, absolute (60) or relative to the estimate (1%)") from None
    if not (math.isfinite(v) and v > 0):
        raise EstimateError(f"--within {text}: give a positive half-width, absolute (60) or relative to the estimate (1%)")
    return (v / 100.0, True) if relative else (v, False)


def is_look(n: int) -> bool:
    """Whether the stopping rule is applied after run ``n`` (1-based): after each of the first
    :data:`LOOKS_DENSE`, then every ``n // LOOKS_DENSE`` runs (about every 1.6 %)."""
    return n <= LOOKS_DENSE or n % (n // LOOKS_DENSE) == 0


@dataclass(frozen=True)
class Question:
    """What to estimate and when to stop (docs/estimate.md).

    ``metric``: a run figure (:data:`desmon.estimate.measures.METRICS`). Its mean, or with
    ``at_least`` the probability that it reaches that value. ``within``: the half-width to
    reach, absolute or (``relative``) a fraction of the estimate; with ``below`` the
    question is a threshold ("is it below X?") and ``within`` the indifference half-width
    around X (relative: a fraction of X). ``confidence``: 1 - delta; ``alpha`` and ``beta``:
    the threshold test's error probabilities (1 - confidence each, unless given). ``range``:
    the range every run's value lies in (seconds: ``[0, horizon]`` unless given; counts
    need one for their mean). ``max_runs``, ``timeout`` (wall seconds): the budget."""

    metric: str = DEFAULT_METRIC
    within: float = 0.05
    relative: bool = True
    confidence: float = 0.95
    at_least: float | None = None
    below: float | None = None
    alpha: float | None = None
    beta: float | None = None
    range: tuple[float, float] | None = None
    max_runs: int = 10_000
    timeout: float | None = None

    @property
    def kind(self) -> str:
        return "probability" if self.at_least is not None else "mean"

    @property
    def delta(self) -> float:
        return 1.0 - self.confidence

    @property
    def interval_confidence(self) -> float:
        """The confidence of the guaranteed interval: ``confidence``, or ``1 - alpha`` when it answers a mean's threshold."""
        return 1.0 - self.alpha if (self.below is not None and self.kind == "mean" and self.alpha is not None) else self.confidence

    def check(self) -> None:
        """Every field's value, or a one-line EstimateError naming the flag and the fix."""
        if not isinstance(self.metric, str):
            raise EstimateError(f"--metric {self.metric!r}: give a run figure's name, e.g. exposure_s")
        check_metric(self.metric)
        self._check_types()
        self._check_confidence()
        w = self.within
        if isinstance(w, bool) or not (isinstance(w, (int, float)) and math.isfinite(w) and w > 0):
            raise EstimateError(f"--within {w!r}: give a positive half-width, absolute (--within 60) or relative to the estimate (--within 1%)")
        if self.kind == "probability" and not self.relative and w >= 0.5:
            raise EstimateError(
                f"--within {w:g}: a probability lies in [0, 1], so a half-width of 0.5 or more is reached at once; give a smaller one "
                "(e.g. --within 0.01) or one relative to the estimate (--within 5%)"
            )
        if isinstance(self.max_runs, bool) or not isinstance(self.max_runs, int) or self.max_runs < 2:
            raise EstimateError(f"--max-runs {self.max_runs!r}: give a whole number of runs, 2 or more")
        if self.timeout is not None and not (math.isfinite(self.timeout) and self.timeout > 0):
            raise EstimateError(f"--timeout {self.timeout!r}: give a positive number of seconds")
        for flag, v in (("--at-least", self.at_least), ("--below", self.below)):
            if v is not None and not math.isfinite(v):
                raise EstimateError(f"{flag} {v!r}: give a finite number")
        self._check_test()
        self._check_range()

    def _check_types(self) -> None:
        """The Python API's fields of the types the command line gives (a text "5" or a
        bool is no number here), and ``range`` a pair."""
        for flag, v in (("--at-least", self.at_least), ("--below", self.below), ("--alpha", self.alpha), ("--beta", self.beta),
                        ("--timeout", self.timeout)):
            if v is not None:
                check_number(flag, v, error=EstimateError, low=None, infinite=True)
        if not isinstance(self.relative, bool):
            raise EstimateError(f"relative = {self.relative!r}: give True (--within 5%) or False (--within 60)")
        if self.range is not None:
            if not isinstance(self.range, (tuple, list)) or len(self.range) != 2:
                raise EstimateError(f"--range {self.range!r}: give two numbers, the lower first, e.g. --range 0 50")
            for v in self.range:
                check_number("--range", v, error=EstimateError, low=None, infinite=True)

    def _check_confidence(self) -> None:
        c = self.confidence
        if isinstance(c, bool) or not (isinstance(c, (int, float)) and math.isfinite(c) and 0.0 < c < 1.0):
            raise EstimateError(f"--confidence {c!r}: give a confidence strictly between 0 and 1, e.g. 0.99 (or 0.95)")
        if not 0.0 < 1.0 - c < 1.0:
            raise EstimateError(f"--confidence {c!r}: so close to 0 that 1 - confidence rounds to 1; give a confidence such as 0.9, 0.95 or 0.99")

    def _check_test(self) -> None:
        if self.below is None:
            for flag, v in (("--alpha", self.alpha), ("--beta", self.beta)):
                if v is not None:
                    raise EstimateError(f"{flag} {v:g} sets an error probability of the threshold test: add --below X, or drop {flag}")
            return
        for flag, v in (("--alpha", self.alpha), ("--beta", self.beta)):
            if v is not None and not (math.isfinite(v) and 0.0 < v < 0.5):
                raise EstimateError(f"{flag} {v!r}: give an error probability above 0 and below 0.5, e.g. 0.01")
        used = (("--alpha", self.alpha), ("--beta", self.beta)) if self.kind == "probability" else (("--alpha", self.alpha),)
        unset = [flag for flag, v in used if v is None]  # (these take 1 - confidence)
        if unset and not self.delta < 0.5:
            raise EstimateError(
                f"--confidence {self.confidence:.10g} leaves the threshold test an error probability of 1 - confidence = {self.delta:.10g}, "
                f"0.5 or more, no better than a coin: give a confidence above 0.5 (e.g. 0.95) or set {' and '.join(unset)}"
            )
        if self.kind == "mean" and self.alpha is not None and self.confidence != Question.confidence:
            raise EstimateError(
                f"confidence {self.confidence:.10g} and alpha {self.alpha:.10g} both set the confidence of a mean's threshold test, "
                "whose interval is at 1 - alpha: give one of them"
            )
        if self.beta is not None and self.kind == "mean":
            raise EstimateError(
                "--beta applies to Wald's test of a probability (with --at-least); a mean's threshold is tested with its "
                "confidence sequence, whose one error probability is --alpha: drop --beta"
            )
        if self.kind == "probability" and not 0.0 < self.below < 1.0:
            raise EstimateError(f"--below {self.below:g}: a probability's threshold lies strictly between 0 and 1, e.g. --below 0.05")

    def _check_range(self) -> None:
        if self.range is None:
            return
        if self.kind == "probability":
            raise EstimateError("--range bounds a mean's values; with --at-least each run counts as yes or no: drop --range")
        lo, hi = self.range
        if not (math.isfinite(lo) and math.isfinite(hi) and hi > lo):
            raise EstimateError(f"--range {lo:g} {hi:g}: give two finite numbers, the lower first, e.g. --range 0 50")
        if not math.isfinite(hi - lo):
            raise EstimateError(f"--range {lo:g} {hi:g}: a range this wide has no finite width in double precision; give a narrower one")

    def half_width_goal(self, estimate: float) -> float:
        """The half-width at which the estimation stops (``within``, or that share of ``|estimate|``)."""
        return self.within * abs(estimate) if self.relative else self.within

    def indifference(self) -> float:
        """The threshold test's indifference half-width around ``below``."""
        assert self.below is not None
        return self.within * abs(self.below) if self.relative else self.within

    def to_json(self) -> dict[str, Any]:
        out = asdict(self)
        out["range"] = list(self.range) if self.range is not None else None
        return out


@dataclass(frozen=True)
class Estimate:
    """An estimation's outcome: the point estimate, the guaranteed interval and its method,
    the approximation beside it, the runs used, why it stopped, and the threshold's answer."""

    scenario: str
    deployer: str
    seed: int
    horizon: float
    question: Question
    interval: Interval
    approximation: Interval
    status: str
    range: tuple[float, float] | None = None
    #: why the range is narrower than ``[0, horizon]`` (:func:`~desmon.estimate.measures.range_basis`), if it is
    range_basis: str | None = None
    answer: str | None = None
    test_method: str | None = None
    low_value: float = math.nan
    high_value: float = math.nan
    #: how the runs' world differs from the scenario file as written, as given on the command
    #: line (``-p hours=0.1``, ``--timing exponential``, ``--no-signals``; empty: not at all)
    world: tuple[str, ...] = ()

    @property
    def runs(self) -> int:
        return self.interval.n

    @property
    def complete(self) -> bool:
        return self.status in (PRECISE, DECIDED)

    def to_json(self) -> dict[str, Any]:
        q, iv, ap = self.question, self.interval, self.approximation
        return {
            "scenario": self.scenario, "deployer": self.deployer, "seed": self.seed, "horizon_s": self.horizon,
            "question": q.to_json(), "kind": q.kind, "status": self.status, "complete": self.complete, "runs": self.runs,
            "estimate": iv.estimate, "low": iv.low, "high": iv.high, "half_width": iv.half_width, "confidence": q.interval_confidence,
            "method": iv.method,
            "approximation": {"low": _finite(ap.low), "high": _finite(ap.high), "method": ap.method},
            "range": list(self.range) if self.range is not None else None, "range_basis": self.range_basis,
            "answer": self.answer, "test_method": self.test_method,
            "min_value": self.low_value, "max_value": self.high_value, "world": list(self.world),
        }


def _finite(x: float) -> float | None:
    return x if math.isfinite(x) else None


class Tracker:
    """The question's statistics over the runs so far: :meth:`add` a run's value, :meth:`stop`
    at a look (whether the question is answered), :meth:`result` the intervals."""

    def __init__(self, question: Question, value_range: tuple[float, float] | None) -> None:
        q = self.question = question
        self.test: WaldTest | None = None
        self.mean: BettingSequence | None = None
        self.share: ProportionSequence | None = None
        if q.kind == "probability":
            self.share = ProportionSequence(q.delta)
            if q.below is not None:
                a = q.alpha if q.alpha is not None else q.delta
                b = q.beta if q.beta is not None else q.delta
                self.test = WaldTest(q.below, q.indifference(), a, b)
        else:
            assert value_range is not None
            # a mean's threshold: the sequence at confidence 1 - alpha answers it, its bets sized for
            # the indifference half-width; an estimate's, for the half-width it stops at
            goal = q.half_width_goal if q.below is None else (lambda _estimate: q.indifference())
            self.mean = BettingSequence(value_range[0], value_range[1], 1.0 - q.interval_confidence, goal=goal)
        self.values: list[float] = []
        self.answer: str | None = None
        self._last: Interval | None = None

    def add(self, value: float) -> None:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise EstimateError(f"a run gave {value!r} for {self.question.metric}, which is no finite number: nothing can be estimated from it")
        self.values.append(value)
        if self.mean is not None:
            self.mean.add(value)
        else:
            assert self.share is not None and self.question.at_least is not None
            hit = value >= self.question.at_least
            self.share.add(hit)
            if self.test is not None:
                self.test.add(hit)

    @property
    def last(self) -> Interval | None:
        """The interval at the latest look (None before the first)."""
        return self._last

    def interval(self) -> Interval:
        seq = self.mean if self.mean is not None else self.share
        assert seq is not None
        self._last = seq.interval()
        return self._last

    def stop(self) -> bool:
        """At a look: whether the question is answered (the answer kept in ``answer``)."""
        q = self.question
        if self.test is not None:
            self.answer = self.test.answer
            if self.answer is not None:
                self.interval()
            return self.answer is not None
        iv = self.interval()
        if q.below is not None:
            eps = q.indifference()
            if iv.high < q.below:
                self.answer = "yes"
            elif iv.low >= q.below:
                self.answer = "no"
            elif q.below - eps <= iv.low and iv.high <= q.below + eps:
                self.answer = "indifferent"
            return self.answer is not None
        return iv.half_width <= q.half_width_goal(iv.estimate)

    def result(self) -> tuple[Interval, Interval]:
        """The guaranteed interval at the last run, and the approximation printed beside it."""
        iv = self._last if self._last is not None and self._last.n == len(self.values) else self.interval()
        if self.share is not None:
            return iv, clopper_pearson(self.share.yes, self.share.n, self.question.delta)
        assert self.mean is not None
        # at the guaranteed one's confidence, inside the proven range
        return iv, normal_interval(self.values, 1.0 - self.question.interval_confidence, (self.mean.low, self.mean.high))


def world_horizon(scenario: Any, until: float | None) -> float:
    """The simulated seconds of each run: ``until``, or the scenario's horizon (a fleet and an
    ``until`` past the horizon refused, as desmon run refuses them)."""
    from desmon.sim.fleet import is_fleet
    from desmon.sim.world import world_of

    if is_fleet(scenario):
        raise EstimateError(
            f"{scenario.name!r} is a fleet of robots: desmon estimate runs one robot per run; estimate a single-robot scenario"
        )
    horizon = float(world_of(scenario).horizon)
    if until is not None:
        check_number("--until", until, error=EstimateError, low=None, infinite=True)
        if not (math.isfinite(until) and 0 < until <= horizon):
            raise EstimateError(f"--until {until:g}: give a positive number of simulated seconds, at most the horizon of {horizon:g} s")
        return float(until)
    return horizon


def with_world(scenario: Any, changes: dict[str, Any]) -> Any:
    """``scenario`` with these fields of its World replaced (``timing``, ``phases``, ``signals``); unchanged without any."""
    if not changes:
        return scenario
    from dataclasses import replace

    from desmon.sim.world import world_of

    return replace(scenario, world=replace(world_of(scenario), **changes))


def run_value(scenario: Any, deployer: Any, seed: int, until: float | None, metric: str, guard: Any = None, collector: Any = None) -> float:
    """``metric`` of one run of ``scenario`` in the SimPy world with world seed ``seed`` (the
    world told that only ``metric`` is read: it skips the work no other output needs).

    The world is built, run and dropped within one :func:`~desmon.sim.collector.collector_relaxed`:
    the collection at its end scans the run's garbage only, the caller's heap frozen out of it
    (collected inside the run, the world would still be alive, and a full collection of the
    whole heap would follow to free it); ``collector``: the
    :class:`~desmon.sim.collector.Collector` it shares with the caller's other runs."""
    from desmon.sim.collector import Collector

    collector = collector if collector is not None else Collector()
    with collector.relaxed(collect=False):
        return _figure(scenario, deployer, seed, until, metric, guard, collector)


def _figure(scenario: Any, deployer: Any, seed: int, until: float | None, metric: str, guard: Any, collector: Any) -> float:
    from desmon.sim.engine import SimWorld
    from desmon.sim.metrics import run_figures

    world = SimWorld(scenario, deployer=deployer, seed=seed, until=until, guard=guard, reads=(metric,), collector=collector)
    result = world.run()
    figures = run_figures(result.metrics, len(result.violations))
    figures[LONGEST] = longest_exposure(world.exposure.intervals)
    return value_of(figures, metric)


def serial_values(scenario: Any, deployer: Any, seed: int, until: float | None, metric: str, guard: Any = None) -> Iterator[float]:
    """The runs' values in seed order, computed here one after the other."""
    from desmon.sim.collector import Collector

    i = 0
    collector = Collector()  # the runs' garbage is collected once it adds up, not after each
    seeds = RunSeeds(seed)
    while True:
        (s,) = seeds.batch(i, 1)
        yield run_value(scenario, deployer, s, until, metric, guard, collector)
        i += 1


def _consume(tracker: Tracker, source: Iterable[float], progress: Callable[[Tracker], None] | None, clock: Callable[[], float],
             started: float | None = None) -> str:
    """Feed ``tracker`` the values of ``source`` until the question is answered or the budget is
    spent; the status (the source is closed then, which ends the runs in flight). A run the
    time limit stopped under way (:class:`~desmon.deployment.guard.ReactionStopped` out of
    the source) counts as the time limit reached, the run left out."""
    from desmon.deployment.guard import ReactionStopped

    q = tracker.question
    status = VALUES_ENDED  # unless the loop below ends otherwise
    started = clock() if started is None else started
    it = iter(source)
    try:
        for n, value in _stoppable(enumerate(it, 1), ReactionStopped):
            if value is None:
                status = TIMEOUT
                break
            tracker.add(value)
            done = (tracker.test is not None or is_look(n)) and tracker.stop()
            if progress is not None:
                progress(tracker)
            if done:
                status = DECIDED if q.below is not None else PRECISE
                break
            if n >= q.max_runs:
                status = MAX_RUNS
                break
            if q.timeout is not None and clock() - started >= q.timeout:
                status = TIMEOUT
                break
    finally:
        close = getattr(it, "close", None)
        if close is not None:
            close()
    if not tracker.values:
        if status == TIMEOUT:
            raise EstimateError(
                f"--timeout {q.timeout:g}: the time was up before the first run ended, so there is no interval; give a longer "
                "--timeout, or shorter runs (--until S)"
            )
        raise EstimateError("no run was made: the values' source gave none")
    return status


def _stoppable(pairs: Iterator[tuple[int, float]], stopped: type[BaseException]) -> Iterator[tuple[int, float | None]]:
    """``pairs`` as they come; ``(n, None)`` in place of the run the time limit stopped under way
    (the exception itself, or SimPy's copy of it caused by it), then no more."""
    n = 0
    while True:
        try:
            n, value = next(pairs)
        except StopIteration:
            return
        except BaseException as exc:
            if isinstance(exc, stopped) or isinstance(exc.__cause__, stopped):
                yield n + 1, None
                return
            raise
        yield n, value


def estimate(
    scenario: Any, question: Question | None = None, *, deployer: Any = "desmon", seed: int = 0, until: float | None = None,
    values: Iterable[float] | None = None, progress: Callable[[Tracker], None] | None = None, guard: Any = None,
    clock: Callable[[], float] = time.monotonic,
) -> Estimate:
    """Estimate ``question`` (a :class:`Question`; the mean exposure to +-5 % at 95 % unless
    given) over independent runs of ``scenario`` in the SimPy world (module docstring).

    ``values``: the runs' values in seed order if computed elsewhere (Dask batches); else
    the runs are made here. ``progress(tracker)`` is called after every run. The result's
    ``status`` says whether it stopped as asked or INCOMPLETE (``max-runs``, ``timeout``),
    with the interval of the runs made so far."""
    q = question if question is not None else Question()
    q.check()
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise EstimateError(f"--seed {seed!r}: give a whole number, 0 or more")
    horizon = world_horizon(scenario, until)
    _check_alarms_rendered(q.metric, scenario)
    value_range, basis = _value_range(q, horizon, scenario)
    tracker = Tracker(q, value_range if q.kind == "mean" else None)
    if values is not None or q.timeout is None:
        source = values if values is not None else serial_values(scenario, deployer, seed, until, q.metric, guard)
        status = _consume(tracker, source, progress, clock)
    else:  # runs made here: the time limit also stops a run under way, at its next reaction
        from desmon.deployment.guard import Guard

        guard = guard if guard is not None else Guard()
        started = clock()
        with guard.watching(lambda: TIMEOUT if clock() - started >= q.timeout else ""):  # type: ignore[operator]
            status = _consume(tracker, serial_values(scenario, deployer, seed, until, q.metric, guard), progress, clock, started)
    iv, approx = tracker.result()
    return Estimate(
        scenario=scenario.name, deployer=getattr(deployer, "name", str(deployer)), seed=seed, horizon=horizon, question=q,
        interval=iv, approximation=approx, status=status, range=value_range if q.kind == "mean" else None, range_basis=basis,
        answer=tracker.answer if status in (PRECISE, DECIDED) else None,
        test_method=_test_method(tracker, status) if q.below is not None else None,
        low_value=min(tracker.values), high_value=max(tracker.values),
    )


def _value_range(q: Question, horizon: float, scenario: Any) -> tuple[tuple[float, float] | None, str | None]:
    """The range every run's value is taken to lie in, and why where it is not the
    horizon's or is the user's narrower one; an EstimateError where the range desmon
    proves answers the question without a run, or a mean has no range."""
    known = natural_range(q.metric, horizon, scenario)
    value_range = q.range or known
    basis = range_basis(q.metric, horizon, scenario) if q.range is None and q.kind == "mean" else None
    if q.range is None and known is not None:
        _refuse_known(q, known, horizon, basis or range_basis(q.metric, horizon, scenario))
    if q.range is not None and known is not None and (q.range[0] > known[0] or q.range[1] < known[1]):
        basis = (f"--range as given, narrower than the [{known[0]:,.6g}, {known[1]:,.6g}] desmon can prove for {q.metric}: "
                 "the guarantee holds only if no run can fall outside the range given (a run that does is refused)")
    if q.kind == "mean" and value_range is None:
        raise EstimateError(
            f"--metric {q.metric} is a count with no bound known in advance, which a guaranteed interval of its mean needs: "
            "declare the range every run's count lies in (--range 0 50), or estimate a probability (--at-least 1)"
        )
    return value_range, basis


def _check_alarms_rendered(metric: str, scenario: Any) -> None:
    """An EstimateError for a figure of the detectors' alarms in a world that renders no
    signals (``--no-signals``, or a World with ``signals=False``): no run could alarm."""
    from desmon.sim.metrics import ALARM_FIGURES
    from desmon.sim.world import world_of

    if metric in ALARM_FIGURES and not world_of(scenario).signals:
        raise EstimateError(
            f"--metric {metric} counts the detectors' alarms, and this world renders no sensor signals, so no detector runs: "
            "drop --no-signals (or give the scenario's World signals=True), or estimate a figure of the deployment"
        )


def _refuse_known(q: Question, known: tuple[float, float], horizon: float, basis: str | None) -> None:
    """An EstimateError where ``known`` (the range desmon proves for every run's figure)
    answers the question without a run: a figure every run gives alike (up to the meter's
    rounding), or a threshold no run can reach or every run reaches. Runs could not add
    to it, and a relative precision of a figure that is 0 is never reached."""
    why = basis or ("the World leases no platform" if q.metric == "leased_s" else f"runs of {horizon:,.6g} s")
    lo, hi = known
    if q.kind == "probability":
        assert q.at_least is not None
        p = 0 if q.at_least > hi else 1 if q.at_least <= lo else None
        if p is not None:
            raise EstimateError(
                f"--at-least {q.at_least:g}: {q.metric} lies in [{lo:,.6g}, {hi:,.6g}] in every run ({why}), so the probability "
                f"is {p} without a run; nothing to estimate"
            )
        return
    slack = ROUNDING_S + TASK_SLACK * horizon  # how far natural_range widens a fixed value at each end
    if hi - lo <= 2 * slack + 8 * math.ulp(max(abs(lo), abs(hi), 1.0)):  # (the ends' own rounding: a few units of their last place)
        value = max(lo, hi - slack)
        raise EstimateError(
            f"--metric {q.metric}: every run gives {value:,.6g} s{f' (to within {slack:.2g} s)' if hi > lo else ''}, known without a run: {why}; "
            "nothing to estimate"
        )


#: how a mean's threshold question was (or was not yet) answered by its confidence sequence, by answer
_SEQUENCE_BASIS = {
    "yes": "confidence sequence excludes the threshold", "no": "confidence sequence excludes the threshold",
    "indifferent": "confidence sequence within the indifference band around the threshold",
    None: "confidence sequence still holds the threshold",
}


def _test_method(tracker: Tracker, status: str) -> str:
    """The basis of a threshold question's answer: Wald's test (a probability), or what the
    confidence sequence showed at the last look (a mean)."""
    if tracker.test is not None:
        return tracker.test.METHOD
    return _SEQUENCE_BASIS[tracker.answer if status in (PRECISE, DECIDED) else None]
