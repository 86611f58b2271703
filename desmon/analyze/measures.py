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

import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from desmon.analyze.chain import Chain, build_chain
from desmon.analyze.markov import AnalysisError, MarkovWorld, check_rates, markov_world, no_budget
from desmon.analyze.solve import KRYLOV_TOL, mean_time_to, one_blas_thread, steady_state, transient
from desmon.deployment.exposure import CAUSES
from desmon.model.checks import check_number
from desmon.model.scenario import Scenario

__all__ = ["Analysis", "analyze", "detector_miss", "detector_start_catch", "TOP_STATES"]

#: states listed in the contribution table
TOP_STATES = 8

#: the most evaluation slips per detection rate ``analyze`` renders (each costs about 10 ms)
MAX_TRIALS = 100_000

#: the evaluation's detector of each signal-stream plan (desmon.sim.streams.detector_plan)
_EVALUATED = {"wrench": "force", "tactile": "tactile", "both": "combined"}


def detector_miss(scenario: Scenario, *, phases: int = 1, trials: int = 200, seed: int = 0) -> dict[str, dict[str, float]]:
    """Each graph's probability of missing a slip in each risky action of the task while
    it watches: 1 - its detector's watching rate in
    :func:`~desmon.detectors.evaluation.detection_rates` for the built-in the action is
    like (see :func:`_rates`); 1 for a graph that cannot detect (an input without a
    signal model), 1 - the rate ``World.detection_rates`` gives for one with a given
    rate."""
    return _rates(scenario, phases, trials, seed)[0]


def detector_start_catch(
    scenario: Scenario, *, phases: int = 1, trials: int = 200, seed: int = 0
) -> dict[str, dict[str, dict[float, float]]]:
    """Each graph's probability of catching a slip in each risky action of the task that
    begins while the graph starts (requested, its start latency or warm-up not yet
    over), per start latency of the platforms (graph -> action -> latency -> p): its
    detector's starting rate in :func:`~desmon.detectors.evaluation.detection_rates`.
    0 for a graph that cannot detect or has a given rate (the world lets those alarm
    only while they watch)."""
    return _rates(scenario, phases, trials, seed)[1]


def _trial_seconds(action: str, mean: float) -> float:
    """A mean step duration as the detection trials take it: to the microsecond; a step
    shorter than that (which the trials would render as no time at all) is refused."""
    seconds = round(mean, 6)
    if seconds <= 0:
        raise AnalysisError(
            f"World task: the {action} steps last {mean:g} s on average, under the microsecond the detection trials "
            "time slips to: give them at least 1e-06 s"
        )
    return seconds


def _trials_said(trials: int, watching: bool, action: str, latency: float, k: int, n: int) -> str:
    """The announcement of the ``k``-th of ``n`` batches of detection trials (``watching``
    False: only the slips that begin while a detector starts are drawn)."""
    which = f"{trials:,} slips" if watching else f"the slips that begin while a detector starts, of {trials:,}"
    return f"the detection trials: {which} in {action} after a start latency of {latency:g} s ({k} of {n})"


def _rates(
    scenario: Scenario, phases: int, trials: int, seed: int, budget: Callable[..., None] | None = None, say: Callable[[str], None] | None = None,
) -> tuple[dict[str, dict[str, float]], dict[str, dict[str, dict[float, float]]]]:
    """The watching miss and the starting catch of every graph in every risky action:
    the evaluation's trials for the built-in the action is like, its steps
    Erlang-``phases`` with the action's mean step duration (as the chain times them),
    after a grasp of the task's mean grasp duration, recognised after the world's
    recognition delay and started with each platform's start latency (the watching
    miss: the world's default latency), with the slip direction and kind
    ``World.slip_kinds`` gives there (``trials`` slips, ``seed``); ``say(what)`` before
    each action's trials at each start latency."""
    from desmon.sim.world import detector_plans, world_of

    world = world_of(scenario)
    model = scenario.model
    plans = detector_plans(world, model)
    warmups = tuple(sorted((_EVALUATED[p.kind], p.warmup) for p in plans.values() if p is not None and p.kind in _EVALUATED))
    spans: dict[str, list[float]] = {}
    for step in world.task:
        if step.action in model.risky_actions:
            spans.setdefault(step.action, []).append(step.duration)
    grasps = [s.duration for s in world.task if model.like(s.action) == "grasp"]
    grasp = _trial_seconds("grasp", sum(grasps) / len(grasps)) if grasps else 2.0
    latencies = sorted({world.latency(p.name) for p in model.platforms} | {world.start_latency})
    rates: dict[tuple[str, float], dict[str, tuple[float, float]]] = {}
    for action, durations in spans.items() if warmups else ():  # (no graph with a signal model: no trial would be read)
        for lat in latencies:
            watching = lat == world.start_latency  # (elsewhere only the starting catch is read)
            if say is not None:
                say(_trials_said(trials, watching, action, lat, len(rates) + 1, len(spans) * len(latencies)))
            rates[(action, lat)] = _trial_rates(
                model, world, action, sum(durations) / len(durations), lat, watching,
                dict(grasp=grasp, phases=phases, trials=trials, seed=seed, warmups=warmups, budget=budget),
            )
    return _per_graph(model, plans, world, list(spans), latencies, rates)


def _per_graph(model: Any, plans: dict[str, Any], world: Any, spans: list[str], latencies: list[float],
               rates: dict[tuple[str, float], dict[str, tuple[float, float]]]) -> tuple[dict[str, dict[str, float]], dict[str, dict[str, dict[float, float]]]]:
    """:func:`_rates`' answer, graph by graph over the risky actions ``spans``: the trials'
    ``rates`` of the detector kind each graph runs, or the rate the World gives it (none: it
    cannot detect)."""
    miss: dict[str, dict[str, float]] = {}
    start: dict[str, dict[str, dict[float, float]]] = {}
    for g in model.graphs:
        plan = plans.get(g.name)
        name = _EVALUATED.get(plan.kind) if plan is not None else None
        given = world.given_rate(g.name)
        miss[g.name], start[g.name] = {}, {}
        for action in spans:
            if name is None:  # no signal model: the rate World.detection_rates gives, or none
                miss[g.name][action] = 1.0 - given if given is not None else 1.0
                start[g.name][action] = {lat: 0.0 for lat in latencies}
            else:
                miss[g.name][action] = 1.0 - rates[(action, world.start_latency)][name][0]
                start[g.name][action] = {lat: rates[(action, lat)][name][1] for lat in latencies}
    return miss, start


def _trial_rates(model: Any, world: Any, action: str, duration: float, latency: float, watching: bool, kw: dict[str, Any]) -> dict[str, tuple[float, float]]:
    """:func:`~desmon.detectors.evaluation.detection_rates` of ``action`` (of mean ``duration``)
    after a start latency of ``latency``, with the slip kind the World gives there."""
    from desmon.detectors.evaluation import detection_rates
    from desmon.sim.world import slip_kind

    like = model.like(action)
    direction, kind = slip_kind(world, like)
    return detection_rates(like, _trial_seconds(action, duration), direction, kind, recognition=world.recognition_delay, latency=latency,
                           watching=watching, **kw)


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
    miss: dict[str, dict[str, float]]
    contributions: list[tuple[float, str]] = field(default_factory=list)
    #: the denominators and the split of the figures: seconds per hour (long run) and
    #: per mission of risky time, excluded time, and unmonitored time by cause
    risky_s_per_hour: float | None = None
    risky_s_per_mission: float | None = None
    excluded_s_per_hour: float | None = None
    excluded_s_per_mission: float | None = None
    causes_s_per_hour: dict[str, float] = field(default_factory=dict)
    causes_s_per_mission: dict[str, float] = field(default_factory=dict)
    #: what the chain leaves out of the world it stands for, one line each
    leaves_out: tuple[str, ...] = ()
    #: the mean length of an unmonitored interval (s) in the long run
    mean_unmonitored_interval_s: float | None = None
    residual: float | None = None
    method: str = ""
    transient_error: float = 0.0
    build_s: float = 0.0
    #: wall seconds of the detection trials behind ``miss`` and ``start_catch`` (0 where given)
    trials_s: float = 0.0
    solve_s: float = 0.0
    reactions: int = 0
    chain: Chain | None = None
    #: each graph's probability of catching a slip that begins while it starts (graph ->
    #: action -> start latency -> p)
    start_catch: dict[str, dict[str, dict[float, float]]] = field(default_factory=dict)

    def to_json(self) -> dict[str, Any]:
        def num(x: float | None) -> float | str | None:
            # an infinite mean time (never) is the string "inf"; NaN stays NaN for the strict writer to refuse
            return None if x is None else (x if math.isfinite(x) or x != math.inf else "inf")

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
            "detector_start_catch_probability": {
                g: {a: {f"{lat:g}": p for lat, p in by.items()} for a, by in acts.items()} for g, acts in self.start_catch.items()
            },
            "risky_s_per_hour": num(self.risky_s_per_hour),
            "risky_s_per_mission": num(self.risky_s_per_mission),
            "excluded_s_per_hour": num(self.excluded_s_per_hour),
            "excluded_s_per_mission": num(self.excluded_s_per_mission),
            "unmonitored_by_cause_s_per_hour": {c: num(v) for c, v in self.causes_s_per_hour.items()},
            "unmonitored_by_cause_s_per_mission": {c: num(v) for c, v in self.causes_s_per_mission.items()},
            "mean_unmonitored_interval_s": num(self.mean_unmonitored_interval_s),
            "leaves_out": list(self.leaves_out),
            "contributions": [{"exposure_s_per_hour": round(v, 9), "state": d} for v, d in self.contributions],
            "steady_state_residual": self.residual,
            "transient_method": self.method,
            "transient_error_estimate": self.transient_error,
            "rates": self.world.to_json(),
            "build_s": round(self.build_s, 3),
            "trials_s": round(self.trials_s, 3),
            "solve_s": round(self.solve_s, 3),
            "reactions_run": self.reactions,
        }


def _p0(chain: Chain) -> np.ndarray:
    p0 = np.zeros(chain.n)
    for i, p in chain.initial:
        p0[i] = p
    return p0


def _long_run(chain: Chain, Q: Any, budget: Callable[..., None] = no_budget) -> tuple[float, float, float, list[tuple[float, str]], np.ndarray]:
    pi, residual, _method = steady_state(Q, chain.describe, chain.blocks(), budget, ends=(_p0(chain), chain.unmonitored))
    frac = float(pi @ chain.unmonitored)
    slips = float(pi @ chain.undetected) * 3600.0
    contrib = pi * chain.unmonitored * 3600.0
    top = np.argsort(-contrib)[:TOP_STATES]
    rows = [(float(contrib[i]), chain.describe(int(i))) for i in top if contrib[i] > 0]
    return frac, slips, residual, rows, pi


@one_blas_thread
def _within(chain: Chain, Q: Any, p0: np.ndarray, horizon: float, budget: Callable[..., None] = no_budget) -> float:
    """P(an unmonitored moment in [0, T]): the unmonitored states made absorbing; the
    mass not yet absorbed only shrinks, so the solution stops once it is below
    :data:`~desmon.analyze.solve.SETTLED` (the answer is then exact to that)."""
    import scipy.sparse as sp

    from desmon.analyze.solve import SETTLED, UNIFORM_STEPS, krylov_steps

    target = chain.unmonitored > 0
    if not target.any():
        return 0.0
    keep = sp.diags((~target).astype(float))
    Qa = (keep @ Q).tocsr()
    lam = float(-Qa.diagonal().min()) * 1.02
    if lam * horizon <= UNIFORM_STEPS:
        tr = transient(Qa, p0, horizon, np.zeros((1, chain.n)), method="uniformisation", budget=budget)
        return float(min(1.0, tr.at[target].sum()))
    A = Qa.T.tocsr()
    v, _err, _steps, _t = krylov_steps(horizon, A, p0.astype(float), tol=KRYLOV_TOL, budget=budget,
                                       stop=lambda w: float(w[~target].sum()) < SETTLED)
    left = float(v[~target].sum())
    if not math.isfinite(left):  # a failed solution stays NaN: the report's check refuses it, where [0, 1] would hide it
        return math.nan
    return float(min(1.0, max(0.0, 1.0 - left)))


def _check_trials(trials: object) -> None:
    if isinstance(trials, bool) or not isinstance(trials, int) or not 1 <= trials <= MAX_TRIALS:
        raise AnalysisError(f"--trials {trials!r} must be a whole number from 1 to {MAX_TRIALS:,}: pass e.g. --trials 2000")


def _detection(
    scenario: Scenario, phases: int, trials: int, start_catch: dict[str, Any] | None, budget: Callable[..., None],
    out: list[tuple[dict[str, Any], dict[str, Any]]], say: Callable[[str], None] | None = None,
) -> tuple[dict[str, Any], dict[str, Any]]:
    """The default ``miss`` and ``start_catch`` of :func:`analyze` (a given ``start_catch``
    kept), also appended to ``out``. A budget without a limit (a
    :class:`~desmon.analyze.markov.Budget` with neither a timeout nor a memory limit)
    never raises: the trials do not ask it, so a process that analyses the same task
    again finds them in :func:`~desmon.detectors.evaluation.detection_rates`'s cache."""
    if start_catch is None:
        unlimited = budget is no_budget or (getattr(budget, "timeout", 0) is None and getattr(budget, "max_memory", 0) is None)
        rates = _rates(scenario, phases, trials, 0, None if unlimited else budget, say)
    else:
        rates = (detector_miss(scenario, phases=phases, trials=trials), start_catch)
    out.append(rates)
    return rates


def analyze(
    scenario: Scenario,
    deployer: Any = "desmon",
    *,
    phases: int | None = None, start_failure_p: float | None = None, horizon: float | None = None,
    steady: bool = True, max_states: int | None = None,
    miss: dict[str, float] | None = None, start_catch: dict[str, Any] | None = None,
    trials: int = 200, guard: Any = None,
    progress: Callable[[int], None] | None = None, status: Callable[[str], None] | None = None,
    budget: Callable[..., None] = no_budget,
) -> Analysis:
    """Build the chain of ``scenario`` under ``deployer`` and compute its measures;
    ``progress(n)`` is called as states are explored, ``status(what)`` (a phrase) before
    each batch of detection trials and each solution step. ``miss`` and ``start_catch`` default to :func:`detector_miss` and
    :func:`detector_start_catch` over ``trials`` slips (a given ``miss`` alone: none caught while starting);
    ``budget()``, called as the chain grows and in every solver iteration, raises once spent.
    ``phases``: Erlang phases of a task step (None: the World's, :func:`~desmon.analyze.markov.world_phases`)."""
    say = status or (lambda _what: None)
    mw = markov_world(scenario, phases=phases, start_failure_p=start_failure_p)
    T = scenario.world.horizon if horizon is None else horizon
    check_number("--horizon", T, error=AnalysisError, positive=True, unit=" of seconds")
    check_rates(mw, float(T))
    _check_trials(trials)
    ran: list[tuple[dict[str, Any], dict[str, Any]]] = []  # the detection trials, run once the chain is built (a crash ends it first)
    chain = build_chain(scenario, deployer, mw, max_states=max_states, progress=progress, miss=miss, start_catch=start_catch, guard=guard,
                        budget=budget, detection=None if miss is not None else lambda: _detection(scenario, mw.phases, trials, start_catch, budget, ran, status))
    miss, start_catch = ran[0] if ran else (miss, start_catch)
    t0 = time.perf_counter()
    Q, _exit = chain.generator()
    p0 = _p0(chain)
    frac = slips = residual = pi = None
    rows: list[tuple[float, str]] = []  # (a Budget raises BudgetExceeded past --timeout or --max-memory)
    if steady:
        say(f"solving the steady state of {chain.n:,} states")
        frac, slips, residual, rows, pi = _long_run(chain, Q, budget)
    say(f"solving the exposure over {T:,.0f} s")
    rewards = np.vstack([chain.unmonitored, chain.undetected, chain.risky, chain.excluded, *(chain.causes[c] for c in CAUSES)])
    tr = transient(Q, p0, T, rewards, limit=pi, budget=budget)
    per_mission = float(tr.accumulated[0])
    extra: dict[str, Any] = {
        "risky_s_per_mission": float(tr.accumulated[2]),
        "excluded_s_per_mission": float(tr.accumulated[3]),
        "causes_s_per_mission": {c: float(tr.accumulated[4 + i]) for i, c in enumerate(CAUSES)},
        "leaves_out": leaves_out(scenario, mw, trials),
    }
    if pi is not None:
        extra["risky_s_per_hour"] = float(pi @ chain.risky) * 3600.0
        extra["excluded_s_per_hour"] = float(pi @ chain.excluded) * 3600.0
        extra["causes_s_per_hour"] = {c: float(pi @ chain.causes[c]) * 3600.0 for c in CAUSES}
        extra["mean_unmonitored_interval_s"] = _mean_interval(Q, pi, chain.unmonitored > 0)
    say(f"solving the probability of any exposure within {T:,.0f} s")
    within = _within(chain, Q, p0, T, budget)
    say("solving the mean time to the first exposure")
    mtte = mean_time_to(Q, chain.unmonitored > 0, p0, budget)
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
        start_catch=dict(start_catch or {}),
        contributions=rows,
        residual=residual,
        method=tr.method,
        transient_error=tr.error,
        build_s=chain.build_s,
        trials_s=chain.trials_s,
        solve_s=time.perf_counter() - t0,
        reactions=chain.reactions,
        chain=chain,
        **extra,
    )


def _mean_interval(Q: Any, pi: np.ndarray, target: np.ndarray) -> float | None:
    """The mean length of an unmonitored interval in the long run: the long-run
    unmonitored fraction over the rate at which the chain enters unmonitored states
    (None when it never does)."""
    import scipy.sparse as sp

    if not target.any():
        return None
    C = sp.csr_matrix(Q, copy=True)  # Q itself is solved on after this
    C.setdiag(0)
    C.eliminate_zeros()
    into = float(pi[~target] @ (C[~target][:, target] @ np.ones(int(target.sum()))))
    if into <= 0:
        return None
    return float(pi[target].sum()) / into


def kept_across_steps(scenario: Scenario, mw: MarkovWorld, skip: frozenset[str] | set[str] = frozenset()) -> tuple[str, ...]:
    """``graph: a -> b`` for each graph (not in ``skip``) that a rule wants in two consecutive
    steps ``a``, ``b`` of the chain's task (the last step followed by the first): the
    deployer keeps it running across the step change."""
    rules = scenario.model.rules
    actions = [a for a, _d in mw.steps]
    pairs = list(zip(actions, actions[1:] + actions[:1])) if len(actions) > 1 else []
    out: dict[str, list[str]] = {}
    for a, b in pairs:
        both = {g for slot in rules.slots_for(a) for g in slot} & {g for slot in rules.slots_for(b) for g in slot}
        for g in sorted(both - skip):
            if f"{a} -> {b}" not in out.setdefault(g, []):
                out[g].append(f"{a} -> {b}")
    return tuple(f"{g}: {', '.join(steps)}" for g, steps in sorted(out.items()))


def leaves_out(scenario: Scenario, mw: MarkovWorld, trials: int = 200) -> tuple[str, ...]:
    """What the chain leaves out of the world it stands for, one line each: printed with
    every figure of ``desmon analyze`` (docs/analyze.md explains each)."""
    lines = []
    timing = "exponential" if mw.phases == 1 else f"Erlang-{mw.phases}"
    world = scenario.world
    if world is not None and world.timing == "exponential":  # the World's own steps: what desmon run draws
        own = "exponential" if world.phases == 1 else f"Erlang-{world.phases}"
        theirs = f"the simulation's are {own} too" if world.phases == mw.phases else f"the simulation's are {own}: --phases {world.phases} matches them"
    else:
        theirs = "the simulation's are fixed: raise --phases to approach it"
    lines.append(
        f"timing: task steps, warm-ups and lease idle times are {timing} with the given means ({theirs}); "
        "start latency, recognition and heartbeat delays are exponential"
    )
    from desmon.sim.world import detector_plans, world_of

    measured = any(p is not None and p.kind in _EVALUATED for p in detector_plans(world_of(scenario), scenario.model).values())
    if mw.slip_rate > 0 and measured:  # (no graph with a signal model: no rate was measured, the given ones are named below)
        lines.append(
            "slip detection: each detector catches a slip with its rate for the action, one while it watches and one while "
            f"it starts, measured by desmon's detection trials ({trials:,} slips per action, not the run's own signals: "
            f"three quarters for the watching rate, good to +-{0.98 / math.sqrt(0.75 * trials):.2f} at 95 %, one quarter for the "
            f"starting rate, +-{0.98 / math.sqrt(0.25 * trials):.2f}; --trials narrows both); a slip before the "
            "monitor recognises its step is caught only by the detectors then watching"
        )
    if mw.dropped:
        lines.append("checker budgets dropped: " + ", ".join(f"{k}={v}" for k, v in mw.dropped) + " (any number of faults may overlap)")
    given = world_of(scenario).detection_rates
    if given:
        lines.append(
            "given detection rates (World.detection_rates, no signal model): "
            + ", ".join(f"{g} {p:g}" for g, p in given)
            + " (the same in every action; the user's figures, not measured)"
        )
    if mw.blind:
        lines.append("cannot detect (an input without a signal model): " + ", ".join(mw.blind) + " (never counted as watching)")
    kept = kept_across_steps(scenario, mw, skip=set(mw.blind) | {g for g, _p in given})
    if mw.slip_rate > 0 and kept:
        lines.append(
            "a detector the rules keep from one step to the next (" + "; ".join(kept) + ") goes on in the world with what it "
            "learned in the step before (a force detector keeps its tare); the trials start it afresh at each step, so the "
            "chain counts that step's misses at a fresh start's rate, which may be higher than the world's (desmon estimate "
            "--metric slips_missed gives the world's)"
        )
    excluded = sorted(scenario.model.unwatched_actions)
    if excluded:
        lines.append("excluded on purpose (watched=False): " + ", ".join(excluded) + " (their seconds are reported apart)")
    lines.append("false alarms are not modelled (desmon run counts them)")
    return tuple(lines)
