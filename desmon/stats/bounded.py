"""The mean of a bounded quantity: a confidence sequence by betting, and the normal interval beside it.

:class:`BettingSequence` is the hedged betting confidence sequence of Waudby-Smith and
Ramdas ("Estimating means of bounded random variables by betting", JRSS-B 86(1), 2024,
their hedged capital process with predictable plug-in bets). For values in ``[low, high]`` with an
unknown mean ``mu``, rescaled to ``[0, 1]``, two gamblers bet on each new value, one
that the mean is above a candidate ``m``, one that it is below::

    K+_t(m) = prod_i (1 + l+_i(m) (y_i - m)),   K-_t(m) = prod_i (1 - l-_i(m) (y_i - m))

with bets ``l+_i(m) = min(L_i, c/m)`` and ``l-_i(m) = min(L_i, c/(1-m))``, where ``L_i``
depends on the values before run ``i`` only (a predictable plug-in of their variance)
and ``c = 0.9`` (:data:`TRUNCATION`). Without a goal, ``L_i = sqrt(2 log(2/delta) /
(s2 i log(1 + i)))``, ``s2`` the plug-in variance: bets that serve every run alike. With
a goal (the half-width ``e`` an estimation stops at, rescaled; at the plug-in mean, for
a goal relative to the estimate: :class:`BettingSequence`'s ``goal``), the bets are
the sample-size-tuned bets Waudby-Smith and Ramdas give for a number of runs known in
advance, ``L_i = sqrt(2 log(2/delta) / (s2 n_i))``, with that number projected from the
runs before: ``n_i = max(i, 2 s2 log(2/delta) / (g e)^2)``, the run where a half-width of
``g e`` is expected (``g`` = :data:`GOAL_REACH`), so ``L_i = g e / s2`` until then.

Each ``L_i``, goal or not, is fixed before value ``i`` is seen, and each bet keeps the
capital above 0 whatever the value: at the true mean both capitals are nonnegative
martingales starting at 1, and by Ville's inequality the chance that either ever
reaches ``2/delta`` is at most ``delta``: the candidates ``m`` where neither has are a
``1 - delta`` confidence interval *at every run at once* -- valid however the number of runs was chosen (stopping once
it is narrow enough, at a deadline, or never), not only at a number fixed in advance.
``K+`` falls and ``K-`` rises with ``m``, so that set is an interval, found by bisection
and intersected with the intervals of the earlier looks.

Assumptions: the runs are independent and identically distributed (independent seeds
of the same world), and every value lies in ``[low, high]`` (checked: a value outside
is refused, since the guarantee would not hold). No other assumption on the
distribution.

:func:`normal_interval` is the textbook interval ``mean +- z s / sqrt(n)``: it assumes
the central limit theorem has taken hold at this ``n`` and a number of runs fixed in
advance; it is printed beside the guaranteed one, labelled as an approximation.

:func:`mean_interval` is the choice every table of a mean over seeds makes between the
two: the betting interval when each value's range is known in advance, else the normal
one. :func:`decimals_for` is how many decimals a printed interval shows.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from desmon.errors import EstimateError

__all__ = ["BettingSequence", "Interval", "normal_interval", "mean_interval", "decimals_for", "check_delta", "BISECTIONS"]

#: bisection steps per bound: the interval is found to 2**-48 of the range
BISECTIONS = 48
#: the largest bet as a share of the candidate's distance to the range's end (any value below 1 keeps the guarantee;
#: Waudby-Smith and Ramdas suggest 1/2 or 3/4, but a run's value is usually far from the range's upper end
#: (a shift's exposure against its horizon), and there the bet against a too-high candidate is capped by
#: this share: the closer to 1, the fewer runs a narrow interval needs when no run comes near that end)
TRUNCATION = 0.9
#: with a goal ``e``, the bets are sized for the run where a half-width of ``GOAL_REACH * e``
#: is projected (module docstring). Any value keeps the guarantee; of 1, 1.5 and 2, 2 took the
#: fewest runs on the robot day, the coffee handover and the coffee shift (CHANGELOG.md has the counts)
GOAL_REACH = 2.0


def check_delta(delta: float, what: str = "delta") -> float:
    """``delta`` (an error probability: 1 - the confidence), or an EstimateError naming ``what``."""
    if isinstance(delta, bool) or not (isinstance(delta, (int, float)) and math.isfinite(delta) and 0.0 < delta < 1.0):
        raise EstimateError(f"{what} {delta!r}: give an error probability strictly between 0 and 1, e.g. 0.01")
    return float(delta)


@dataclass(frozen=True, slots=True)
class Interval:
    """A two-sided interval ``[low, high]`` around ``estimate`` from ``n`` runs, and how it was made."""

    estimate: float
    low: float
    high: float
    n: int
    method: str

    @property
    def half_width(self) -> float:
        return (self.high - self.low) / 2.0

    def contains(self, value: float) -> bool:
        return self.low <= value <= self.high


class BettingSequence:
    """The hedged betting confidence sequence (see the module docstring) for values in
    ``[low, high]`` at confidence ``1 - delta``: :meth:`add` each run's value in seed
    order, :meth:`interval` at any run."""

    METHOD = "betting confidence sequence (Waudby-Smith & Ramdas 2024), valid at every run"

    def __init__(self, low: float, high: float, delta: float, goal: Callable[[float], float] | None = None) -> None:
        """``goal``: the half-width at which the caller stops, for an estimate (``goal(estimate)``,
        in the values' units; e.g. ``lambda m: 0.01 * abs(m)``), or None: the bets' size (module docstring)."""
        if not (math.isfinite(low) and math.isfinite(high) and high > low):
            raise EstimateError(f"range [{low:g}, {high:g}]: give a finite range whose upper end is above its lower end")
        self.low, self.high, self.delta = float(low), float(high), check_delta(delta)
        self._y: list[float] = []  # the values rescaled to [0, 1]
        self._bets: list[float] = []  # L_i, fixed before value i was seen
        self._sum = 0.0
        self._sq = 0.0  # sum of (y_i - mean after i)^2: the plug-in variance
        self._raw: list[float] = []
        self._lo, self._hi = 0.0, 1.0  # the intersection of the looks so far, rescaled
        self._log_level = math.log(2.0 / self.delta)
        if goal is not None and not callable(goal):
            raise EstimateError(f"goal {goal!r}: give the half-width as a function of the estimate (e.g. lambda m: 0.01 * abs(m)), or None")
        self.goal = goal

    @property
    def n(self) -> int:
        return len(self._y)

    @property
    def values(self) -> tuple[float, ...]:
        return tuple(self._raw)

    def add(self, value: float) -> None:
        """One more run's value; outside ``[low, high]`` is an EstimateError (the guarantee needs the range)."""
        x = float(value)
        if not (math.isfinite(x) and self.low <= x <= self.high):
            raise EstimateError(
                f"run {self.n + 1} gave {value!r}, outside the range [{self.low:g}, {self.high:g}] the interval's guarantee assumes; "
                "declare a range that holds every run's value (--range LOW HIGH)"
            )
        t = self.n + 1
        variance = (0.25 + self._sq) / t  # the plug-in variance of the values before this one
        self._bets.append(self._bet(t, variance))
        y = (x - self.low) / (self.high - self.low)
        self._y.append(y)
        self._raw.append(x)
        self._sum += y
        mean = (0.5 + self._sum) / (t + 1)
        self._sq += (y - mean) ** 2

    def _bet(self, t: int, variance: float) -> float:
        """``L_t`` from the plug-in variance of the values before run ``t`` (and the goal, if any)."""
        runs = t * math.log1p(t)
        if self.goal is not None:
            span = self.high - self.low
            e = self.goal(self.low + span * (0.5 + self._sum) / t) / span  # at the plug-in mean of the values before
            g = GOAL_REACH * e
            reach = g * g if math.isfinite(e) else 0.0  # (a float product overflows to inf, where ** raises)
            if reach > 0.0:  # (a goal so small that its square underflows sizes no bet: the default sizing; one so
                # large that it overflows sizes them for the runs so far)
                runs = max(float(t), 2.0 * variance * self._log_level / reach)
        return math.sqrt(2.0 * self._log_level / (variance * runs))

    def _log_capital(self, m: float, sign: int, y: np.ndarray, bets: np.ndarray) -> float:
        """log K+(m) (``sign`` +1) or log K-(m) (-1) over the values so far."""
        room = m if sign > 0 else 1.0 - m
        lam = bets if room <= 0.0 else np.minimum(bets, TRUNCATION / room)
        return float(np.sum(np.log1p(sign * lam * (y - m))))

    def _bound(self, sign: int, y: np.ndarray, bets: np.ndarray) -> float:
        """The lower (``sign`` +1) or upper (-1) end, rescaled: the last candidate known rejected
        on that side (so the interval holds every candidate not rejected)."""
        rejected, kept = (0.0, 1.0) if sign > 0 else (1.0, 0.0)
        if self._log_capital(rejected, sign, y, bets) < self._log_level:
            return rejected
        for _ in range(BISECTIONS):
            mid = (rejected + kept) / 2.0
            if self._log_capital(mid, sign, y, bets) >= self._log_level:
                rejected = mid
            else:
                kept = mid
        return rejected

    def interval(self) -> Interval:
        """The interval at this run: the candidates no bet has rejected, intersected with the earlier looks'."""
        n = self.n
        if n == 0:
            return Interval(math.nan, self.low, self.high, 0, self.METHOD)
        y, bets = np.asarray(self._y), np.asarray(self._bets)
        lo, hi = self._bound(+1, y, bets), self._bound(-1, y, bets)
        if max(lo, self._lo) <= min(hi, self._hi):  # (empty only where the guarantee failed: keep this look's)
            lo, hi = max(lo, self._lo), min(hi, self._hi)
        self._lo, self._hi = lo, hi
        span = self.high - self.low
        return Interval(math.fsum(self._raw) / n, self.low + lo * span, self.low + hi * span, n, self.METHOD)


def normal_interval(values: list[float] | tuple[float, ...], delta: float, value_range: tuple[float, float] | None = None) -> Interval:
    """``mean +- z_{1-delta/2} s / sqrt(n)`` (Student's t quantile below 30 runs): the CLT
    approximation, not guaranteed (module docstring). Needs 2 runs or more. With the
    ``value_range`` every value is known to lie in, its ends are kept inside it (a mean of
    values in ``[a, b]`` lies in ``[a, b]``: an end beyond it only says less)."""
    from scipy.special import ndtri, stdtrit  # the quantiles of scipy.stats' norm and t, without importing scipy.stats

    n = len(values)
    mean = math.fsum(values) / n if n else math.nan
    if n < 2:
        return Interval(mean, -math.inf, math.inf, n, NORMAL_METHOD)
    sd = math.sqrt(math.fsum((v - mean) ** 2 for v in values) / (n - 1))
    q = float(stdtrit(n - 1, 1 - delta / 2)) if n < 30 else float(ndtri(1 - delta / 2))
    low, high = mean - q * sd / math.sqrt(n), mean + q * sd / math.sqrt(n)
    if value_range is not None:
        low, high = max(low, value_range[0]), min(high, value_range[1])
    return Interval(mean, low, high, n, NORMAL_METHOD)


NORMAL_METHOD = "normal approximation (CLT), not guaranteed"


def mean_interval(values: list[float] | tuple[float, ...], delta: float, value_range: tuple[float, float] | None = None) -> Interval:
    """The ``1 - delta`` interval of the mean of independent runs' ``values``, as a table of a mean
    over seeds prints it: the betting confidence sequence (guaranteed) when every value is known to
    lie in ``value_range``, else :func:`normal_interval` (an approximation; infinite ends below 2 values)."""
    if value_range is None:
        return normal_interval(list(values), delta)
    cs = BettingSequence(value_range[0], value_range[1], delta)
    for v in values:
        cs.add(v)
    return cs.interval()


def decimals_for(half_width: float, digits: int = 2) -> int:
    """How many decimals an interval of ``half_width`` prints with: enough for ``digits``
    significant digits of its half-width, the same for its estimate and both its ends
    (``[9.5, 13.9]``, not ``[9.539, 13.9]``); 0 for a half-width that is zero or not finite."""
    if not (math.isfinite(half_width) and half_width > 0.0):
        return 0
    return max(0, digits - 1 - math.floor(math.log10(half_width)))
