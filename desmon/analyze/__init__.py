"""Exact exposure: the continuous-time Markov chain of a scenario's real deployer.

``desmon analyze SCENARIO`` and :func:`analyze` build the chain from the checker's own
transition system (:mod:`desmon.analyze.chain`), with the rates of the scenario's World
(:mod:`desmon.analyze.markov`), and solve it exactly (:mod:`desmon.analyze.solve`) for
the measures of :mod:`desmon.analyze.measures`. docs/analyze.md explains them.
"""

from desmon.analyze.markov import AnalysisError, MarkovWorld, markov_world
from desmon.analyze.chain import Chain, ChainState, build_chain, BudgetExceeded
from desmon.analyze.measures import Analysis, analyze, detector_miss

__all__ = [
    "AnalysisError", "BudgetExceeded", "MarkovWorld", "markov_world", "Chain", "ChainState", "build_chain",
    "Analysis", "analyze", "detector_miss",
]
