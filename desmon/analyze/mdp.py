"""How far a deployer's placements are from the best ones: the MDP of its placement choices.

Where a reaction may place a graph on several acceptable platforms, a deployer's choice
among them is a tie-break: the desmon deployer takes the first acceptable platform in
the model's declaration order (after its preferences), the paper's Algorithm 2 too. The
MDP lets that choice free: at every reaction the controller picks the order of the
platforms the *same* deployer code then runs under (one transition system per order of
the model's platforms, all on the checker's store), so its actions are exactly the
placements that deployer can make. Every other race (task steps, faults, notices,
start latencies) is as in the chain.

:func:`optimality_gap` computes the minimum and maximum long-run exposure over all
such placement policies by policy iteration (each policy evaluated exactly: its steady
state and its bias, then improved greedily event by event, until no choice changes),
the deployer's own exposure (the declaration order everywhere), and the first state
(in breadth-first order from the start) where the optimal policy's choice differs from
the deployer's and is strictly better.

**The best is a relaxation.** The MDP's policies decide on the whole chain state, which
holds facts no deployer sees: a component broken that the monitor has not yet noticed,
a start still under way. So the best (and the worst) may be out of any deployer's
reach. :class:`Gap` says how much: it splits the deployer's distance to the best into
the shares of its decisions (the performance-difference identity: a decision's share
is its state's long-run probability under the deployer, times the race's rate, times
the optimal bias lost by the deployer's choice; the shares add up to the gap), reports
the decision with the largest share and the part of the gap decided in states with an
unnoticed fact, and gives the best a deployer can be written to reach: the best of the
fixed platform orders (the same deployer code with the model's platforms reordered
once, for every reaction).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from desmon.analyze.chain import BudgetExceeded, Builder, ChainState, recognised, rewards
from desmon.analyze.markov import AnalysisError, MarkovWorld, markov_world, no_budget
from desmon.analyze.solve import one_blas_thread, steady_state
from desmon.deployment.control import ControlRules
from desmon.model.events import ActionChange
from desmon.model.scenario import Scenario

__all__ = ["Gap", "optimality_gap", "MAX_ORDERS"]

#: the most platform orders (permutations) the MDP's actions range over
MAX_ORDERS = 24


@dataclass(frozen=True)
class Gap:
    """The deployer's long-run exposure between the best and the worst placements."""

    deployer: str
    states: int
    exposure_s_per_hour: float
    min_s_per_hour: float
    max_s_per_hour: float
    iterations: int
    #: the first state where the best placement differs: (state, event, deployer's commands, best commands)
    differs: tuple[str, str, str, str] | None
    #: the decision with the largest share of the gap: (state, event, deployer's, best's, share of the gap)
    largest: tuple[str, str, str, str, float] | None = None
    #: the part of the gap decided in states where a broken component is not yet noticed
    unobservable_share: float = 0.0
    #: the best fixed platform order (names, s/h): a deployer that can be written
    best_order: tuple[tuple[str, ...], float] | None = None
    #: the decisions' shares added up, over the gap: 1 to the solver's precision (the identity, checked)
    shares_total: float = 0.0
    #: the MDP and its reward vector (for :func:`desmon.analyze.export.export_placements`)
    model: tuple[Any, np.ndarray] | None = field(default=None, compare=False, repr=False)

    @property
    def above_optimal(self) -> float:
        """(deployer - minimum) / minimum."""
        return (self.exposure_s_per_hour - self.min_s_per_hour) / self.min_s_per_hour if self.min_s_per_hour else 0.0

    def to_json(self) -> dict[str, Any]:
        return {
            "deployer": self.deployer, "states": self.states, "exposure_s_per_hour": self.exposure_s_per_hour,
            "min_s_per_hour": self.min_s_per_hour, "max_s_per_hour": self.max_s_per_hour,
            "above_optimal": self.above_optimal, "policy_iterations": self.iterations,
            "first_difference": None if self.differs is None else dict(zip(("state", "event", "deployer", "optimal"), self.differs)),
            "largest_share": None if self.largest is None else dict(zip(("state", "event", "deployer", "optimal", "share"), self.largest)),
            "unobservable_share": self.unobservable_share,
            "best_order": None if self.best_order is None else {"platforms": list(self.best_order[0]), "s_per_hour": self.best_order[1]},
            "shares_total": self.shares_total,
        }

    def text(self) -> str:
        lines = [
            f"Placements ({self.deployer}, MDP of {self.states:,} states): deployer {self.exposure_s_per_hour:.3f} s/h; "
            f"best {self.min_s_per_hour:.3f}, worst {self.max_s_per_hour:.3f} s/h; {100 * self.above_optimal:.3g} % above optimal"
        ]
        if self.best_order is not None:
            order, value = self.best_order
            lines.append(
                f"  best and worst are over policies that see the whole world, unnoticed faults included: no deployer need "
                f"reach them; the best fixed platform order ({', '.join(order)}) gives {value:.3f} s/h"
            )
        if self.largest is not None:
            state, event, mine, best, share = self.largest
            lines.append(
                f"  largest share of the gap ({100 * share:.3g} %): in [{state}] on {event}: deployer {mine}; optimal {best}; "
                f"{100 * self.unobservable_share:.3g} % of the gap is decided where a broken component is not yet noticed"
            )
        if self.differs is not None:
            state, event, mine, best = self.differs
            lines.append(f"  first differing decision (breadth-first): in [{state}] on {event}: deployer {mine}; optimal {best}")
        return "\n".join(lines) + "\n"


def _ordered(scenario: Scenario, order: tuple[str, ...]) -> Scenario:
    model = scenario.model
    by = {p.name: p for p in model.platforms}
    return replace(scenario, model=replace(model, platforms=tuple(by[n] for n in order)))


def _commands(cmds: tuple) -> str:
    return ", ".join(f"{'start' if start else 'stop'} {g}@{p}" for start, g, p in cmds) or "nothing"


class _MDP:
    """States, and per state its races; a race's alternatives are the distinct outcome
    distributions of the deployer under each platform order (index 0: the declared one)."""

    def __init__(self, scenario: Scenario, deployer: Any, mw: MarkovWorld, max_states: int | None, guard: Any = None,
                 budget: Any = no_budget) -> None:
        self.budget = budget
        names = tuple(p.name for p in scenario.model.platforms)
        if math.factorial(len(names)) > MAX_ORDERS:  # a cut list of orders would make "best" a lie
            raise AnalysisError(
                f"--placements: the model has {len(names)} platforms, {math.factorial(len(names)):,} orders to choose among; "
                f"it handles at most {MAX_ORDERS} (4 platforms): analyze without --placements"
            )
        orders = list(itertools.permutations(names))
        self.orders = orders
        self.builders = [
            Builder(_ordered(scenario, o), deployer, mw, where="" if k == 0 else
                    f"with the platforms in the order {', '.join(o)}, one --placements tries (desmon verify runs the declared order)",
                    guard=guard)
            for k, o in enumerate(orders)
        ]
        self.main = self.builders[0]
        self.max_states = max_states
        self.states: list[ChainState] = []
        self.index: dict[ChainState, int] = {}
        # per state: list of (rate, event, [alternative: ((prob, target index), ...)], [commands of each alternative])
        self.races: list[list[tuple[float, Any, list[tuple[tuple[int, float], ...]], list[str]]]] = []
        # per state and race: the alternative each platform order takes (index into the race's alternatives)
        self.which: list[list[tuple[int, ...]]] = []

    def _id(self, s: ChainState) -> int:
        j = self.index.get(s)
        if j is None:
            j = self.index[s] = len(self.states)
            self.states.append(s)
            if self.max_states is not None and len(self.states) > self.max_states:
                raise BudgetExceeded(f"the placement MDP has more than --max-states {self.max_states} states: raise it")
        return j

    def build(self) -> None:
        key0 = self.main.system.initial()
        s0 = ChainState(key0, 0, 0, (), tuple(sorted(key0.down)), ())
        if self.main.mw.recognition_delay == 0:
            _r, _e, outs = self.main._deliver(s0, ActionChange(recognised(self.main.mw.steps[0][0])), 1.0)
            s0 = max(outs, key=lambda o: o[0])[1]
        self._id(s0)
        i = 0
        while i < len(self.states):
            self.budget()
            s = self.states[i]
            per_builder = [list(b.slots(s)) for b in self.builders]
            races, which = [], []
            for k, (rate, event, outcomes) in enumerate(per_builder[0]):
                alts: list[tuple[tuple[int, float], ...]] = []
                cmds: list[str] = []
                chosen = []
                for slots in per_builder:
                    dist = tuple(sorted((self._id(t), p) for p, t, _c in slots[k][2]))
                    if dist not in alts:
                        alts.append(dist)
                        cmds.append(_commands(max(slots[k][2], key=lambda o: o[0])[2]))
                    chosen.append(alts.index(dist))
                races.append((rate, event, alts, cmds))
                which.append(tuple(chosen))
            self.races.append(races)
            self.which.append(which)
            i += 1


def _generator(mdp: _MDP, policy: list[list[int]]):  # type: ignore[no-untyped-def]
    import scipy.sparse as sp

    rows, cols, vals = [], [], []
    for i, races in enumerate(mdp.races):
        for (rate, _e, alts, _c), a in zip(races, policy[i]):
            for j, p in alts[a]:
                if j != i:
                    rows.append(i)
                    cols.append(j)
                    vals.append(rate * p)
    n = len(mdp.states)
    off = sp.csr_matrix((vals, (rows, cols)), shape=(n, n))
    return (off - sp.diags(np.asarray(off.sum(axis=1)).ravel())).tocsr()


@one_blas_thread
def _evaluate(Q, r: np.ndarray, describe, blocks: np.ndarray, with_pi: bool = False, budget: Any = no_budget):  # type: ignore[no-untyped-def]
    """The gain (long-run reward per second) and a bias vector of the policy's chain
    (and its steady state, ``with_pi``); ``budget()`` is asked between the solver's steps."""
    import scipy.sparse.linalg as sla

    pi, _res, _m = steady_state(Q, describe, blocks, budget=budget)
    budget()
    g = float(pi @ r)
    ref = int(np.argmax(pi))
    keep = np.flatnonzero(np.arange(Q.shape[0]) != ref)
    sub = Q[keep][:, keep].tocsc()
    rhs = (g - r)[keep]
    with np.errstate(all="ignore"):
        h, _info = sla.bicgstab(sub, rhs, rtol=1e-13, atol=0.0, maxiter=max(1000, 4 * len(keep)))
    if not np.all(np.isfinite(h)) or np.abs(sub @ h - rhs).max() > 1e-8 * max(1.0, np.abs(rhs).max()):
        h = sla.spsolve(sub, rhs, permc_spec="MMD_AT_PLUS_A")
    bias = np.zeros(Q.shape[0])
    bias[keep] = h
    return (g, bias, pi) if with_pi else (g, bias)


def _improve(mdp: _MDP, policy: list[list[int]], h: np.ndarray, sign: float) -> bool:
    changed = False
    for i, races in enumerate(mdp.races):
        for k, (_rate, _e, alts, _c) in enumerate(races):
            if len(alts) < 2:
                continue
            vals = [sign * sum(p * h[j] for j, p in alt) for alt in alts]
            cur = policy[i][k]
            best = int(np.argmin(vals))
            if vals[best] < vals[cur] - 1e-9 * max(1.0, abs(vals[cur])):
                policy[i][k] = best
                changed = True
    return changed


def _optimise(mdp: _MDP, r: np.ndarray, sign: float, describe, blocks: np.ndarray) -> tuple[float, list[list[int]], np.ndarray, int]:  # type: ignore[no-untyped-def]
    policy = [[0] * len(races) for races in mdp.races]
    for it in range(1, 100):
        g, h = _evaluate(_generator(mdp, policy), r, describe, blocks, budget=mdp.budget)
        if not _improve(mdp, policy, h, sign):
            return g, policy, h, it
    raise AnalysisError("policy iteration did not settle in 100 rounds")


def optimality_gap(scenario: Scenario, deployer: Any = "desmon", *, phases: int = 1, start_failure_p: float | None = None,
                   max_states: int | None = None, guard: Any = None, budget: Any = no_budget) -> Gap:
    """The deployer's long-run exposure between the best and worst placements (module
    docstring); ``budget()`` (:class:`~desmon.analyze.markov.Budget`) is asked while the MDP
    is built and between the solver's steps, and raises once the time or memory is spent."""
    mw = markov_world(scenario, phases=phases, start_failure_p=start_failure_p)
    mdp = _MDP(scenario, deployer, mw, max_states, guard, budget)
    mdp.build()
    # rewards of the MDP's states (the chain's definition)
    from desmon.analyze.chain import Chain

    holder = Chain(mdp.states, np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(0), mw, mdp.main.system)
    rewards(holder, ControlRules(scenario.model), {})
    r = holder.unmonitored

    def describe(i: int) -> str:
        return holder.describe(i)

    blocks = holder.blocks()
    own = [[0] * len(races) for races in mdp.races]
    g_own, _h, d_own = _evaluate(_generator(mdp, own), r, describe, blocks, with_pi=True, budget=budget)
    g_min, best, h_min, it1 = _optimise(mdp, r, 1.0, describe, blocks)
    g_max, _worst, _h, it2 = _optimise(mdp, r, -1.0, describe, blocks)
    differs = None
    for i, races in enumerate(mdp.races):  # breadth-first order: the first state where the best choice is strictly better
        for k, (_rate, event, alts, cmds) in enumerate(races):
            a = best[i][k]
            if a != 0:
                v0 = sum(p * h_min[j] for j, p in alts[0])
                va = sum(p * h_min[j] for j, p in alts[a])
                if va < v0 - 1e-9 * max(1.0, abs(v0)):
                    differs = (describe(i), str(event), cmds[0], cmds[a])
                    break
        if differs is not None:
            break
    largest, unobservable, total = _shares(mdp, best, h_min, d_own, g_own - g_min, describe)
    orders = [_evaluate(_generator(mdp, [[w[b] for w in which] for which in mdp.which]), r, describe, blocks, budget=budget)[0] for b in range(len(mdp.orders))]
    b = int(np.argmin(orders))
    return Gap(
        mdp.main.system.deployer_name, len(mdp.states), g_own * 3600.0, g_min * 3600.0, g_max * 3600.0, it1 + it2, differs,
        model=(mdp, r), largest=largest, unobservable_share=unobservable, best_order=(mdp.orders[b], orders[b] * 3600.0), shares_total=total,
    )


def _unnoticed(s: ChainState) -> bool:
    """Whether chain state ``s`` holds a broken component the repository does not know of."""
    return set(s.phys_failed) != set(s.key.failed) or set(s.phys_down) != set(s.key.down)


def _shares(mdp: _MDP, best: list[list[int]], h: np.ndarray, d: np.ndarray, gap: float, describe):  # type: ignore[no-untyped-def]
    """The decision with the largest share of ``gap`` (the deployer's gain minus the
    best's) and the part of it decided in states with an unnoticed fault (module
    docstring: share = d(i) x rate x (bias after the deployer's choice - after the best's))."""
    if gap <= 1e-12:
        return None, 0.0, 0.0
    top, top_share, hidden, total = None, 0.0, 0.0, 0.0
    for i, races in enumerate(mdp.races):
        for k, (rate, event, alts, cmds) in enumerate(races):
            a = best[i][k]
            if a == 0:
                continue
            share = d[i] * rate * (sum(p * h[j] for j, p in alts[0]) - sum(p * h[j] for j, p in alts[a])) / gap
            total += share
            if share > top_share:
                top, top_share = (i, k, event, cmds[0], cmds[a]), share
            if _unnoticed(mdp.states[i]):
                hidden += share
    if top is None:
        return None, 0.0, total
    i, _k, event, mine, theirs = top
    return (describe(i), str(event), mine, theirs, top_share), min(1.0, max(0.0, hidden)), total
