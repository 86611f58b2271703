"""The exact measures of a scenario's chain: :func:`analyze` and :class:`Analysis`.

Long-run (steady state of the chain's one closed class):

* ``long_run_unmonitored_fraction`` — the fraction of time a risky action runs while a
  slot of what the rules want has no valid, ready detector (the ``unmonitored`` label);
* ``exposure_s_per_hour`` — the same, in seconds per hour;
* ``undetected_slips_per_hour`` — slips per hour that go undetected: slips arrive at
  ``World.slip_rate`` while an object is in the hand (a risky action); one arriving in
  an unmonitored state is missed, one arriving while detectors run is missed with
  the product of their miss probabilities (1 - each detector's evaluated TP rate);
* ``contributions`` — which states the unmonitored time comes from.

Per mission (transient from the initial state over the horizon T, default the World's):

* ``exposure_s_per_mission`` — expected unmonitored seconds in [0, T] (what ``desmon run
  --timing exponential`` measures by simulation);
* ``p_exposure_within_T`` — the probability of any unmonitored moment in [0, T];
* ``mean_time_to_exposure_s`` — the expected time to the first unmonitored moment.
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from desmon.analyze.chain import Chain, build_chain
from desmon.analyze.markov import AnalysisError, MarkovWorld, markov_world
from desmon.analyze.solve import KRYLOV_TOL, mean_time_to, one_blas_thread, steady_state, transient
from desmon.model.checks import check_number
from desmon.model.scenario import Scenario

__all__ = ["Analysis", "analyze", "detector_miss", "TOP_STATES"]

#: states listed in the contribution table
TOP_STATES = 8

#: the evaluation's detector of each signal-stream plan (desmon.sim.streams.detector_plan)
_EVALUATED = {"wrench": "force", "tactile": "tactile", "both": "combined"}


def detector_miss(scenario: Scenario, *, trials: int = 200, seed: int = 0) -> dict[str, float]:
    """Each graph's probability of missing a slip: 1 - the TP rate of its detector in
    the evaluation of Tables 1-2 (``desmon evaluate``: ``trials`` slips up and down,
    ``seed``); 1 for a graph whose device kinds have no signal model."""
    from desmon.sim.streams import detector_plan
    from desmon.sim.world import world_of

    world = world_of(scenario)
    tp = _tp_rates(trials, seed)
    out = {}
    for g in scenario.model.graphs:
        streams = frozenset(world.signal_of(k) or "" for k in g.device_kinds)
        plan = detector_plan(streams) if "" not in streams else None
        name = _EVALUATED.get(plan.kind) if plan is not None else None
        out[g.name] = 1.0 - float(np.mean(tp[name])) if name in tp else 1.0
    return out


@functools.lru_cache(maxsize=8)
def _tp_rates(trials: int, seed: int) -> dict[str, list[float]]:
    """Each detector's TP rates (slips down and up) in the Tables 1-2 evaluation, once per process."""
    from desmon.detectors.evaluation import evaluate_actions

    tp: dict[str, list[float]] = {}
    for cell in evaluate_actions(trials, seed):
        if cell.kind == "TP":
            tp.setdefault(cell.detector, []).append(cell.rate)
    return tp


@dataclass
class Analysis:
    """What ``desmon analyze`` computes (see the module docstring)."""

    scenario: str
    deployer: str
    states: int
    transitions: int
    horizon_s: float
    world: MarkovWorld
    long_run_unmonitored_fraction: float | None
    exposure_s_per_hour: float | None
    undetected_slips_per_hour: float | None
    exposure_s_per_mission: float | None
    p_exposure_within_T: float | None
    mean_time_to_exposure_s: float
    miss: dict[str, float]
    contributions: list[tuple[float, str]] = field(default_factory=list)
    residual: float | None = None
    method: str = ""
    transient_error: float = 0.0
    build_s: float = 0.0
    solve_s: float = 0.0
    reactions: int = 0
    chain: Chain | None = None

    def to_json(self) -> dict[str, Any]:
        def num(x: float | None) -> float | str | None:
            return None if x is None else (x if math.isfinite(x) else "inf")

        return {
            "scenario": self.scenario,
            "deployer": self.deployer,
            "states": self.states,
            "transitions": self.transitions,
            "horizon_s": self.horizon_s,
            "long_run_unmonitored_fraction": num(self.long_run_unmonitored_fraction),
            "exposure_s_per_hour": num(self.exposure_s_per_hour),
            "undetected_slips_per_hour": num(self.undetected_slips_per_hour),
            "exposure_s_per_mission": num(self.exposure_s_per_mission),
            "p_exposure_within_T": num(self.p_exposure_within_T),
            "mean_time_to_exposure_s": num(self.mean_time_to_exposure_s),
            "detector_miss_probability": self.miss,
            "contributions": [{"exposure_s_per_hour": round(v, 9), "state": d} for v, d in self.contributions],
            "steady_state_residual": self.residual,
            "transient_method": self.method,
            "transient_error_bound": self.transient_error,
            "rates": self.world.to_json(),
            "build_s": round(self.build_s, 3),
            "solve_s": round(self.solve_s, 3),
            "reactions_run": self.reactions,
        }


def _p0(chain: Chain) -> np.ndarray:
    p0 = np.zeros(chain.n)
    for i, p in chain.initial:
        p0[i] = p
    return p0


def _long_run(chain: Chain, Q: Any) -> tuple[float, float, float, list[tuple[float, str]], np.ndarray]:
    pi, residual, _method = steady_state(Q, chain.describe, chain.blocks())
    frac = float(pi @ chain.unmonitored)
    slips = float(pi @ chain.undetected) * 3600.0
    contrib = pi * chain.unmonitored * 3600.0
    top = np.argsort(-contrib)[:TOP_STATES]
    rows = [(float(contrib[i]), chain.describe(int(i))) for i in top if contrib[i] > 0]
    return frac, slips, residual, rows, pi


@one_blas_thread
def _within(chain: Chain, Q: Any, p0: np.ndarray, horizon: float) -> float:
    """P(an unmonitored moment in [0, T]): the unmonitored states made absorbing; the
    mass not yet absorbed only shrinks, so the solution stops once it is below
    :data:`~desmon.analyze.solve.SETTLED` (the answer is then exact to that)."""
    import scipy.sparse as sp

    from desmon.analyze.solve import FIRST_CHUNK, SETTLED, UNIFORM_STEPS, expv

    target = chain.unmonitored > 0
    if not target.any():
        return 0.0
    keep = sp.diags((~target).astype(float))
    Qa = (keep @ Q).tocsr()
    lam = float(-Qa.diagonal().min()) * 1.02
    if lam * horizon <= UNIFORM_STEPS:
        tr = transient(Qa, p0, horizon, np.zeros((1, chain.n)), method="uniformisation")
        return float(min(1.0, tr.at[target].sum()))
    A = Qa.T.tocsr()
    v = p0.astype(float)
    t, chunk = 0.0, FIRST_CHUNK
    while t < horizon:
        span = min(chunk, horizon - t)
        v, _err, _steps = expv(span, A, v, tol=KRYLOV_TOL)
        t, chunk = t + span, chunk * 2
        if float(v[~target].sum()) < SETTLED:
            break
    return float(min(1.0, max(0.0, 1.0 - v[~target].sum())))


def analyze(
    scenario: Scenario,
    deployer: Any = "desmon",
    *,
    phases: int = 1,
    start_failure_p: float | None = None,
    horizon: float | None = None,
    steady: bool = True,
    max_states: int | None = None,
    miss: dict[str, float] | None = None,
    progress: Callable[[int], None] | None = None,
    status: Callable[[str], None] | None = None,
) -> Analysis:
    """Build the chain of ``scenario`` under ``deployer`` and compute its measures;
    ``progress(n)`` is called as states are explored, ``status(what)`` before each
    solution step (long on a large chain)."""
    say = status or (lambda _what: None)
    mw = markov_world(scenario, phases=phases, start_failure_p=start_failure_p)
    T = scenario.world.horizon if horizon is None else horizon
    check_number("--horizon", T, error=AnalysisError, positive=True, unit=" of seconds")
    if miss is None:
        miss = detector_miss(scenario)
    chain = build_chain(scenario, deployer, mw, max_states=max_states, progress=progress, miss=miss)
    t0 = time.perf_counter()
    Q, _exit = chain.generator()
    p0 = _p0(chain)
    frac = slips = residual = pi = None
    rows: list[tuple[float, str]] = []
    if steady:
        say(f"the steady state of {chain.n:,} states")
        frac, slips, residual, rows, pi = _long_run(chain, Q)
    say(f"the exposure over {T:,.0f} s")
    tr = transient(Q, p0, T, np.vstack([chain.unmonitored, chain.undetected]), limit=pi)
    per_mission = float(tr.accumulated[0])
    say(f"the probability of any exposure within {T:,.0f} s")
    within = _within(chain, Q, p0, T)
    say("the mean time to the first exposure")
    mtte = mean_time_to(Q, chain.unmonitored > 0, p0)
    return Analysis(
        scenario=scenario.name,
        deployer=chain.system.deployer_name,
        states=chain.n,
        transitions=int(len(chain.rates)),
        horizon_s=float(T),
        world=mw,
        long_run_unmonitored_fraction=frac,
        exposure_s_per_hour=None if frac is None else frac * 3600.0,
        undetected_slips_per_hour=slips,
        exposure_s_per_mission=per_mission,
        p_exposure_within_T=within,
        mean_time_to_exposure_s=mtte,
        miss=dict(miss),
        contributions=rows,
        residual=residual,
        method=tr.method,
        transient_error=tr.error,
        build_s=chain.build_s,
        solve_s=time.perf_counter() - t0,
        reactions=chain.reactions,
        chain=chain,
    )
