"""``desmon estimate``: how sure is a figure of the simulated world? Independent runs of the
SimPy world (signals, scripted faults, load walks: what ``desmon run`` simulates), one
seed each, until a guaranteed confidence interval of the figure's mean -- or of the
probability that it reaches a value -- is as narrow as asked, or a threshold question
is answered with stated error probabilities.

:func:`estimate` runs the loop (:mod:`desmon.estimate.loop`) over the statistics of
:mod:`desmon.stats`; :mod:`desmon.estimate.measures` names the figures and the ranges
their values lie in. docs/estimate.md states each method, its assumptions and a reference.
"""

from desmon.estimate.loop import Estimate, Question, estimate, run_seed, run_value
from desmon.estimate.measures import METRICS

__all__ = ["Estimate", "Question", "estimate", "run_seed", "run_value", "METRICS"]
