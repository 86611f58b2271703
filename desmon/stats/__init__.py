"""Guaranteed statistics over independent runs: pure functions and small accumulators, no engine.

* :mod:`desmon.stats.bounded`: the mean of a value bounded in a known range (the
  unmonitored seconds of a shift lie in ``[0, horizon]``) -- a betting confidence
  sequence, valid at every run however the number of runs is chosen, and the normal
  (CLT) interval beside it, labelled as an approximation, and :func:`mean_interval`,
  which of the two a table of a mean over seeds prints;
* :mod:`desmon.stats.proportion`: a probability -- a beta-binomial mixture confidence
  sequence, the fixed-n Clopper-Pearson interval beside it, and Wald's sequential test
  of a threshold with stated error probabilities.

``desmon estimate`` (:mod:`desmon.estimate`) feeds them the runs of the SimPy world;
docs/estimate.md states each method, its assumptions and a reference.
"""

from desmon.stats.bounded import BettingSequence, Interval, decimals_for, mean_interval, normal_interval
from desmon.stats.proportion import ProportionSequence, Verdict, WaldTest, clopper_pearson

__all__ = ["BettingSequence", "Interval", "normal_interval", "mean_interval", "decimals_for", "ProportionSequence", "Verdict", "WaldTest", "clopper_pearson"]
