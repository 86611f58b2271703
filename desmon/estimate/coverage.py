"""The coverage self-test: do the intervals hold the true value as often as they promise?

On a scenario whose exact value is known (``desmon analyze``'s chain, for the Markov world
its runs simulate: exponential timing, signals off), :func:`estimations` runs many
independent estimations (estimation ``j`` with seed ``seed + j``: disjoint runs) and
:func:`coverage` counts those whose interval holds the exact value. A method with confidence ``1 - delta``
must hold it in at least ``1 - delta`` of them; :func:`fails` judges the count with a
one-sided binomial test, so that a correct method fails it with probability at most
``FALSE_ALARM`` while a method that misses more often than promised is caught.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

from desmon.estimate.loop import Estimate, Question, estimate

__all__ = ["Coverage", "coverage", "estimations", "guaranteed", "fails", "FALSE_ALARM"]

#: the chance a correct method fails :func:`fails` (one-sided binomial test)
FALSE_ALARM = 0.001


@dataclass(frozen=True)
class Coverage:
    """How many of ``total`` intervals held ``exact``; ``runs``: the runs the estimations made in all."""

    exact: float
    inside: int
    total: int
    runs: int
    delta: float

    @property
    def share(self) -> float:
        return self.inside / self.total

    @property
    def failed(self) -> bool:
        return fails(self.total - self.inside, self.total, self.delta)

    def __str__(self) -> str:
        return (f"{self.inside}/{self.total} intervals held the exact value {self.exact:.6g} ({100 * self.share:.1f} %, "
                f"promised {100 * (1 - self.delta):g} %; {self.runs:,} runs): {'FAILED' if self.failed else 'passed'}")


def fails(misses: int, total: int, delta: float) -> bool:
    """Whether ``misses`` of ``total`` intervals missing is too many for a method whose miss
    probability is at most ``delta``: P(Binomial(total, delta) >= misses) < :data:`FALSE_ALARM`."""
    from scipy.stats import binom

    return misses > 0 and float(binom.sf(misses - 1, total, delta)) < FALSE_ALARM


def estimations(
    scenario: Any, question: Question, *, count: int, seed: int = 0, until: float | None = None, deployer: Any = "desmon",
) -> list[Estimate]:
    """``count`` independent estimations of ``question`` on ``scenario``: estimation ``j`` with seed ``seed + j``."""
    return [estimate(scenario, question, deployer=deployer, seed=seed + j, until=until) for j in range(count)]


def guaranteed(e: Estimate) -> tuple[float, float]:
    """The guaranteed interval of an estimation (what :func:`coverage` judges unless told otherwise)."""
    return e.interval.low, e.interval.high


def coverage(found: list[Estimate], exact: float, interval: Callable[[Estimate], tuple[float, float]] = guaranteed) -> Coverage:
    """How many of the estimations' intervals (``interval(e)``: the guaranteed one unless given;
    a test hands in a mutated one, which must fail) hold ``exact``."""
    inside = sum(lo <= exact <= hi for lo, hi in map(interval, found))
    return Coverage(exact, inside, len(found), sum(e.runs for e in found), found[0].question.delta)
