"""A probability: a confidence sequence for it, Clopper-Pearson beside it, and Wald's sequential test.

Each run says yes or no (say: was the unmonitored exposure of this shift 60 s or more?),
independently with the same unknown probability ``p``.

* :class:`ProportionSequence` is the beta-binomial mixture confidence sequence (Robbins,
  "Statistical methods related to the law of the iterated logarithm", Ann. Math. Statist.
  41, 1970; Howard, Ramdas, McAuliffe and Sekhon, "Time-uniform, nonparametric,
  nonasymptotic confidence sequences", Ann. Statist. 49, 2021): after ``n``
  runs with ``s`` yes, the likelihood ratio of a Beta(1/2, 1/2) mixture against ``p``,
  ``B(1/2 + s, 1/2 + n - s) / B(1/2, 1/2) / (p^s (1-p)^(n-s))``, is a nonnegative
  martingale under ``p``; by Ville's inequality it reaches ``1/delta`` with chance at
  most ``delta`` ever, so the ``p`` where it has not are a ``1 - delta`` interval at every
  run at once (valid under optional stopping). It is the sequential form of the exact
  binomial interval; no assumption but independent, identically distributed runs.
* :func:`clopper_pearson` is the exact binomial interval for a number of runs fixed in
  advance (Clopper and Pearson, Biometrika 26, 1934): printed beside the sequence,
  labelled, since a number of runs chosen by looking at the data voids it.
* :class:`WaldTest` is Wald's sequential probability ratio test (Wald, "Sequential tests
  of statistical hypotheses", Ann. Math. Statist. 16, 1945) of "p is below ``threshold``":
  it weighs ``p1 = threshold - indifference`` against ``p0 = threshold + indifference``
  and answers yes once the likelihood ratio reaches ``1/alpha``, no once it falls to
  ``beta``. Those thresholds (Ville's inequality, not Wald's approximations) bound the
  error probabilities: a yes when ``p >= p0`` has chance at most ``alpha``, a no when
  ``p <= p1`` at most ``beta``; inside the indifference region either answer may come.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from desmon.errors import EstimateError
from desmon.stats.bounded import BISECTIONS, Interval, check_delta

__all__ = ["ProportionSequence", "clopper_pearson", "WaldTest", "Verdict", "CLOPPER_PEARSON_METHOD"]

#: the mixture's prior: Beta(1/2, 1/2) (Jeffreys)
PRIOR = 0.5
CLOPPER_PEARSON_METHOD = "Clopper-Pearson at this number of runs: valid only had it been fixed in advance"


class ProportionSequence:
    """The beta-binomial mixture confidence sequence (module docstring): :meth:`add`
    each run's yes (True) or no, :meth:`interval` at any run."""

    METHOD = "beta-binomial mixture confidence sequence (Robbins 1970), valid at every run"

    def __init__(self, delta: float) -> None:
        self.delta = check_delta(delta)
        self.n = 0
        self.yes = 0
        self._lo, self._hi = 0.0, 1.0
        self._log_level = math.log(1.0 / self.delta)

    def add(self, outcome: bool) -> None:
        self.n += 1
        self.yes += bool(outcome)

    def _log_ratio(self, p: float) -> float:
        from scipy.special import betaln, xlog1py, xlogy

        s, f = self.yes, self.n - self.yes
        if (p <= 0.0 and s) or (p >= 1.0 and f):
            return math.inf
        return float(betaln(PRIOR + s, PRIOR + f) - betaln(PRIOR, PRIOR) - xlogy(s, p) - xlog1py(f, -p))

    def _bound(self, rejected: float, kept: float) -> float:
        """The end of the interval between ``kept`` (not rejected) and ``rejected``: the last
        candidate known rejected (the ratio is convex in ``p``, so one crossing)."""
        if self._log_ratio(rejected) < self._log_level:
            return rejected
        for _ in range(BISECTIONS):
            mid = (rejected + kept) / 2.0
            if self._log_ratio(mid) >= self._log_level:
                rejected = mid
            else:
                kept = mid
        return rejected

    def interval(self) -> Interval:
        if self.n == 0:
            return Interval(math.nan, 0.0, 1.0, 0, self.METHOD)
        share = self.yes / self.n  # the ratio is at most 1 there: never rejected
        lo, hi = self._bound(0.0, share), self._bound(1.0, share)
        if max(lo, self._lo) <= min(hi, self._hi):
            lo, hi = max(lo, self._lo), min(hi, self._hi)
        self._lo, self._hi = lo, hi
        return Interval(share, lo, hi, self.n, self.METHOD)


def clopper_pearson(yes: int, n: int, delta: float) -> Interval:
    """The exact binomial ``1 - delta`` interval of ``yes`` in ``n`` runs fixed in advance."""
    from scipy.stats import beta

    if n == 0:
        return Interval(math.nan, 0.0, 1.0, 0, CLOPPER_PEARSON_METHOD)
    lo = 0.0 if yes == 0 else float(beta.ppf(delta / 2, yes, n - yes + 1))
    hi = 1.0 if yes == n else float(beta.ppf(1 - delta / 2, yes + 1, n - yes))
    return Interval(yes / n, lo, hi, n, CLOPPER_PEARSON_METHOD)


@dataclass(frozen=True, slots=True)
class Verdict:
    """A sequential test's answer so far: ``"yes"``, ``"no"``, or ``None`` while undecided."""

    answer: str | None
    n: int
    log_ratio: float
    method: str


class WaldTest:
    """Wald's SPRT of "the probability is below ``threshold``" (module docstring)."""

    METHOD = "Wald's sequential probability ratio test"

    def __init__(self, threshold: float, indifference: float, alpha: float, beta: float) -> None:
        self.p1, self.p0 = threshold - indifference, threshold + indifference
        if not (indifference > 0 and 0.0 < self.p1 and self.p0 < 1.0):
            raise EstimateError(
                f"--below {threshold:g} with an indifference of +-{indifference:g}: the test weighs {self.p1:g} against {self.p0:g}, "
                "which must lie strictly between 0 and 1; give a threshold inside (0, 1) and a narrower --within"
            )
        self.alpha, self.beta = check_delta(alpha, "--alpha"), check_delta(beta, "--beta")
        self.threshold, self.indifference = threshold, indifference
        self._yes = math.log(self.p1 / self.p0)
        self._no = math.log((1 - self.p1) / (1 - self.p0))
        self.log_ratio = 0.0
        self.n = 0
        self.answer: str | None = None

    def add(self, outcome: bool) -> Verdict:
        """One more run; the answer once decided (runs after it change nothing)."""
        if self.answer is None:
            self.n += 1
            self.log_ratio += self._yes if outcome else self._no
            if self.log_ratio >= math.log(1.0 / self.alpha):
                self.answer = "yes"
            elif self.log_ratio <= math.log(self.beta):
                self.answer = "no"
        return self.verdict()

    def verdict(self) -> Verdict:
        return Verdict(self.answer, self.n, self.log_ratio, self.METHOD)
