"""Exact against simulated: the chain's per-mission exposure beside the SimPy world's.

:func:`simulated_exposure` runs the scenario's World under exponential timing (the
Markov world the chain solves: ``World(timing="exponential")``, signals off, so that a
running, ready detector counts as monitoring, as in the chain) for each seed, and
:func:`agreement` puts the chain's expected unmonitored seconds over the horizon beside
the simulation's mean and its 99 % confidence interval (Student's t over the seeds) and,
where every run's value lies in a known range (a mission's ``[0, T]`` seconds), the
guaranteed 99 % interval of :mod:`desmon.stats`, on which :attr:`Agreement.disagrees` decides:
the runs' exposures are skewed (rare long outages), and with few seeds the t interval
excludes the true mean far more often than 1 in 100.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Callable, Sequence

from desmon.analyze.markov import AnalysisError
from desmon.model.scenario import Scenario

__all__ = ["Agreement", "simulated_exposure", "agreement", "markov_scenario", "MIN_SEEDS"]

#: the fewest seeds a confidence interval is computed from
MIN_SEEDS = 3


def markov_scenario(scenario: Scenario, *, phases: int = 1, timing: str = "exponential", start_failure_p: float | None = None) -> Scenario:
    """``scenario`` with its World under ``timing`` (Erlang ``phases``) and signals off;
    ``start_failure_p``, if given, replaces the World's start failure probability (as
    ``desmon analyze --start-failure-p`` does for the chain)."""
    from desmon.sim.world import StartFailure, world_of

    world = replace(world_of(scenario), timing=timing, phases=phases if timing == "exponential" else 1, signals=False)
    if start_failure_p is not None:
        world = replace(world, start_failure=StartFailure(probability=start_failure_p))
    return replace(scenario, world=world)


def simulated_exposure(
    scenario: Scenario, deployer: Any, seeds: Sequence[int], horizon: float, *, phases: int = 1, timing: str = "exponential",
    start_failure_p: float | None = None, progress: Callable[[int], None] | None = None, cause: str | None = None,
    guard: Any = None, budget: Callable[[], None] | None = None,
) -> list[float]:
    """Unmonitored seconds in ``[0, horizon]`` of one simulated run per seed (with
    ``cause``: only those of that cause, one of :data:`desmon.deployment.exposure.CAUSES`);
    ``budget()``, if given, is called before each run (it raises once spent)."""
    from desmon.sim.collector import Collector
    from desmon.sim.engine import simulate

    sc = markov_scenario(scenario, phases=phases, timing=timing, start_failure_p=start_failure_p)
    out = []
    collector = Collector()  # the runs' garbage is collected once it adds up, not after each
    read = ("exposure_s" if cause is None else f"{cause}_s",)  # (no audit, no trace records: nothing here reads them)
    for i, seed in enumerate(seeds):
        if budget is not None:
            budget()
        r = simulate(sc, deployer, seed=seed, until=horizon, guard=guard, collector=collector, reads=read)
        m = r.metrics
        out.append(float(m["unmonitored_exposure_s"] if cause is None else m["unmonitored_by_cause_s"][cause]))
        if progress is not None:
            progress(i + 1)
    return out


@dataclass(frozen=True)
class Agreement:
    """The exact value, the simulation's mean and 99 % confidence interval, and whether
    the exact value lies inside it."""

    exact: float
    mean: float
    low: float
    high: float
    seeds: int
    values: tuple[float, ...]
    #: the guaranteed 99 % interval of the mean where every value is known to lie in a range
    #: (the betting confidence sequence of :mod:`desmon.stats`), else None
    sure: tuple[float, float] | None = None

    @property
    def inside(self) -> bool:
        """Whether the exact value lies in the interval (one that every seed's run agrees
        on exactly, such as a task that always holds an object, has no width: then to
        rounding, 1e-9 relative)."""
        return self._holds(self.low, self.high)

    def _holds(self, low: float, high: float) -> bool:
        """Whether the exact value lies in ``[low, high]``, to rounding (1e-9 of the mean)."""
        slack = 1e-9 * max(1.0, abs(self.mean))
        return low - slack <= self.exact <= high + slack

    @property
    def disagrees(self) -> bool:
        """Whether the simulation shows the exact value wrong: it lies outside the guaranteed
        interval (which excludes a true mean in at most 1 of 100 such comparisons, however
        skewed the runs); without one, outside the Student's t interval."""
        return not (self.inside if self.sure is None else self._holds(*self.sure))

    @property
    def gap(self) -> float:
        """(simulated mean - exact) / exact."""
        return (self.mean - self.exact) / self.exact if self.exact else math.inf

    def to_json(self) -> dict[str, Any]:
        return {
            "exact_s": self.exact, "simulated_mean_s": self.mean, "ci99_low_s": self.low, "ci99_high_s": self.high, "ci99_method": METHOD,
            "seeds": self.seeds, "inside": self.inside, "min_s": min(self.values), "max_s": max(self.values),
            **({"guaranteed99_low_s": self.sure[0], "guaranteed99_high_s": self.sure[1], "guaranteed99_method": SURE_METHOD}
               if self.sure is not None else {}),
            "disagrees": self.disagrees,
        }


def confidence(values: Sequence[float], level: float = 0.99) -> tuple[float, float, float]:
    """(mean, low, high): the two-sided ``level`` interval of the mean (Student's t)."""
    from scipy.special import stdtrit  # Student's t quantile (scipy.stats.t.ppf's own), without importing scipy.stats

    n = len(values)
    if n < MIN_SEEDS:
        raise AnalysisError(f"--simulate {n}: a confidence interval needs at least {MIN_SEEDS} seeds")
    mean = sum(values) / n
    var = sum((v - mean) ** 2 for v in values) / (n - 1)
    half = float(stdtrit(n - 1, 0.5 + level / 2)) * math.sqrt(var / n)
    return mean, mean - half, mean + half


#: how :func:`confidence` makes its interval, as the reports name it
METHOD = "Student's t, not guaranteed"
#: how the guaranteed interval is made, as the reports name it
SURE_METHOD = "betting confidence sequence over the range, guaranteed"


def agreement(exact: float, values: Sequence[float], value_range: tuple[float, float] | None = None) -> Agreement:
    """The exact value beside the 99 % interval of the mean of the simulated ``values``
    (:func:`confidence`), its ends kept inside the ``value_range`` every value lies in (the
    mission's ``[0, T]`` seconds: an end beyond it only says less)."""
    mean, low, high = confidence(values)
    sure = None
    if value_range is not None:
        from desmon.stats import mean_interval

        low, high = max(low, value_range[0]), min(high, value_range[1])
        iv = mean_interval(list(values), 0.01, value_range)
        sure = (iv.low, iv.high)
    return Agreement(exact, mean, low, high, len(values), tuple(values), sure)
