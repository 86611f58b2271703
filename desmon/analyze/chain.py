"""The continuous-time Markov chain of a scenario, built from the checker's own transitions.

A chain state is the checker's state (:class:`~desmon.verify.state.Key`: what the
repository knows, the deployments, the standing errors) plus what the world adds: the
position in the task cycle and its Erlang phase, the components that are *physically*
down (the repository learns of it when the context monitor notices), and the started
detectors whose start latency has not yet passed. Every reaction is the real
deployer's, run by :meth:`TransitionSystem.run_one
<desmon.verify.system.TransitionSystem.run_one>` on the checker's store exactly as
``desmon verify`` runs it (no re-model): starts beyond the outcome prefix succeed, and
each start is a choice point that fails with probability ``start_failure_p``. The
reactions are checked for determinism as ``desmon verify`` checks them (the first
:data:`~desmon.verify.system.RECHECK_FIRST` and every
:data:`~desmon.verify.system.RECHECK_EVERY`-th run twice and compared,
:func:`~desmon.verify.system.same_again`): a deployer that decides at random is refused.

Rates and what they do (:mod:`desmon.analyze.markov`):

* task phase ends (rate phases/duration): the next phase, or the next step; the true
  action changes and, with no recognition delay, the context monitor reports it at once;
* recognition (rate 1/recognition_delay) while the recognised context differs from the
  true action's: the monitor reports the true action;
* a component fails or is repaired (1/MTTF, 1/MTTR): physically at once; the repository
  learns of it at once (no heartbeat) or when the monitor notices (1/heartbeat), which
  reports the component's state *then*;
* a started detector becomes ready (1/start latency of its platform);
* a random requirement change (its rate);
* a load step to a neighbouring level (its rate, split over the neighbours): the
  repository learns it at once;
* a lease: a reaction that raises *no acceptable platform* for a graph requests the
  on-demand platform the simulation would lease (:func:`~desmon.deployment.lease.lease_choice`
  on the store after the reaction); it joins (1/startup_s) and, while it hosts
  nothing, leaves (1/idle_s); the monitor notices joins and leaves like repairs and
  breakdowns.

Where the world differs from what the repository knows (a platform gone, back or a
device broken, repaired, not yet noticed), the Control rules judge a start on the
*physical* facts, as in the simulation, whatever the repository says.

A state is **unmonitored** by the one definition of :mod:`desmon.deployment.exposure`,
which the simulation counts by too: the true action is risky and no rule covers it, or
a slot of its rule has no watching member (deployed, its start latency and warm-up
over, on a physically up platform, every input physically readable, able to detect a
slip). Each unmonitored state has its cause; an action declared ``watched=False`` is
labelled excluded instead.
"""

from __future__ import annotations

import time
from array import array
from dataclasses import dataclass, field, replace
from typing import Any, Callable, Final, Iterator, NamedTuple

import numpy as np

from desmon.deployment.control import ControlRules
from desmon.deployment.exposure import CAUSES, WATCHING, best_state, cause, needs_table
from desmon.deployment.guard import DeployerFault
from desmon.deployment.lease import lease_choice
from desmon.deployment.ports import NO_ACCEPTABLE_PLATFORMS, RaiseError, Start, Stop
from desmon.errors import CheckerError
from desmon.model.events import DeviceEvent, Event, PlatformEvent
from desmon.model.scenario import Scenario
from desmon.model.system import PlatformState
from desmon.sim.processes import recognised_context
from desmon.verify.environment import variable_kind
from desmon.verify.state import Key
from desmon.verify.memory import check_module_state
from desmon.verify.system import RECHECK_EVERY, RECHECK_FIRST, TransitionSystem, crash_of, same_again

from desmon.analyze.markov import AnalysisError, BudgetExceeded, MarkovWorld, chain_bounds, no_budget

__all__ = ["ChainState", "Chain", "Builder", "build_chain", "rewards", "BudgetExceeded", "recognised"]


#: one race out of a state: (rate, the event reacted to or None, ((probability, next state, commands), ...))
Slot = tuple


class ChainState(NamedTuple):
    key: Key
    pos: int  # task step
    phase: int
    phys_failed: tuple[str, ...]  # devices physically failed, sorted
    phys_down: tuple[str, ...]  # platforms physically down (absent on-demand ones included), sorted
    starting: tuple[tuple[str, str], ...]  # (graph, platform) started, not yet ready, sorted
    requested: tuple[str, ...] = ()  # on-demand platforms leased, not yet joined, sorted
    warming: tuple[tuple[str, str, int], ...] = ()  # (graph, platform, Erlang phase) warming up, sorted
    idle: tuple[tuple[str, int], ...] = ()  # (leased platform, Erlang phases of idle time passed), sorted


def _physical(model: Any, rules: Any, failed: tuple[str, ...], down: tuple[str, ...]) -> Callable[[str, str], str | None]:
    """The Control rules' refusal of a start on the physical facts."""
    gone, broken = set(down), set(failed)
    states = {
        p.name: PlatformState(p, p.name not in gone, tuple(d for d in model.devices_on(p.name) if d.name not in broken))
        for p in model.platforms
    }
    return lambda g, pl: rules.start_refusal(g, pl, states.__getitem__)


def _unchanged_by(s: ChainState, live: tuple[tuple[str, str], ...]) -> bool:
    """Whether :meth:`Builder._starting_after` of a reaction that starts and stops nothing
    and leaves the deployments ``live`` gives back ``s``'s own starting, warming and idle
    parts: each still deployed (an idle platform hosting nothing), each part in its order."""
    if s.starting and (not all(pair in live for pair in s.starting) or s.starting != tuple(sorted(set(s.starting)))):
        return False
    if s.warming:
        pairs = {(g, p) for g, p, _k in s.warming}
        if len(pairs) != len(s.warming) or not all(pair in live for pair in pairs) or s.warming != tuple(sorted(s.warming)):
            return False
    return not s.idle or not any(p == q for p, _k in s.idle for _g, q in live)


#: the context the monitor reports for the true action: the simulation's own rule
recognised = recognised_context


@dataclass
class Chain:
    """The chain: states, rates (COO arrays), labels and what each state is."""

    states: list[ChainState]
    rows: np.ndarray
    cols: np.ndarray
    rates: np.ndarray
    world: MarkovWorld
    system: TransitionSystem
    #: 1.0 where the state is unmonitored (risky true action, an uncovered slot)
    unmonitored: np.ndarray = field(default_factory=lambda: np.zeros(0))
    risky: np.ndarray = field(default_factory=lambda: np.zeros(0))
    #: slips per second that go undetected in each state
    undetected: np.ndarray = field(default_factory=lambda: np.zeros(0))
    #: 1.0 where the state is unmonitored for that cause (desmon.deployment.exposure.CAUSES)
    causes: dict[str, np.ndarray] = field(default_factory=dict)
    #: 1.0 where the true action is risky but declared watched=False (excluded)
    excluded: np.ndarray = field(default_factory=lambda: np.zeros(0))
    #: the initial distribution: (state index, probability)
    initial: tuple[tuple[int, float], ...] = ((0, 1.0),)
    build_s: float = 0.0
    #: the wall seconds of the detection trials (``build_chain``'s ``detection``), apart from ``build_s``
    trials_s: float = 0.0
    reactions: int = 0

    @property
    def n(self) -> int:
        return len(self.states)

    def generator(self):  # type: ignore[no-untyped-def]
        """The infinitesimal generator Q (scipy CSR): off-diagonal rates, diagonal -exit rate."""
        import scipy.sparse as sp

        n = self.n
        off = sp.csr_matrix((self.rates, (self.rows, self.cols)), shape=(n, n))
        exit_ = np.asarray(off.sum(axis=1)).ravel()
        return (off - sp.diags(exit_)).tocsr(), exit_

    def blocks(self) -> np.ndarray:
        """A block number per state: states with the same physically broken components
        (faults are the chain's slow events; everything else moves within a block)."""
        ids: dict[tuple, int] = {}
        leased = {p for p, _t in self.world.lease}
        return np.fromiter(
            (ids.setdefault((s.phys_failed, tuple(p for p in s.phys_down if p not in leased)), len(ids)) for s in self.states),
            dtype=np.int64, count=self.n,
        )

    def describe(self, i: int) -> str:
        """One line for state ``i``: the task step, what is known, deployed and down."""
        s = self.states[i]
        action = self.world.steps[s.pos][0]
        parts = [f"{action}" + (f" (phase {s.phase + 1}/{self.world.phases})" if self.world.phases > 1 else "")]
        parts.append(f"context {s.key.context}")
        parts.append("deployed " + (", ".join(f"{g}@{p}" for g, p in s.key.deployments) or "nothing"))
        if s.starting:
            parts.append("starting " + ", ".join(f"{g}@{p}" for g, p in s.starting))
        if s.warming:
            parts.append("warming up " + ", ".join(f"{g}@{p}" for g, p, _k in s.warming))
        parts.extend(self._changes(s))
        down = [*s.phys_failed, *(p for p in s.phys_down if not self.system.model.platform(p).on_demand)]
        if down:
            parts.append("broken " + ", ".join(down))
        known = set(s.key.failed) | set(s.key.down)
        unseen = [c for c in (*s.phys_failed, *s.phys_down) if c not in known]
        if unseen:
            parts.append("not yet noticed " + ", ".join(unseen))
        physical = set(s.phys_failed) | set(s.phys_down)
        back = [c for c in (*s.key.failed, *s.key.down) if c not in physical]
        if back:
            parts.append("up again, not yet noticed " + ", ".join(back))
        if s.key.standing:
            parts.append("errors for " + ", ".join(s.key.standing))
        return "; ".join(parts)

    def _changes(self, s: ChainState) -> Iterator[str]:
        """What run-time changes made of ``s``: loads, requirements, leases."""
        loads = dict(s.key.loads)
        for p, r, _lv, _rate in self.world.loads:
            yield f"{p} {r} load {dict(loads.get(p, ())).get(r, 0):g}"
        for g, reqs in s.key.specs:
            now = set(reqs)
            label = next((c.label for c, _r in self.world.changes if c.graph == g and c.label and set(c.add) <= now), "")
            yield f"{g} requirements {label or 'changed'}"
        joined = [p for p, _t in self.world.lease if p not in s.phys_down]
        if joined:
            yield "leased " + ", ".join(joined)
        if s.requested:
            yield "lease requested " + ", ".join(s.requested)


class Builder:
    """Breadth-first over chain states; one transition system, its reactions memoised."""

    def __init__(self, scenario: Scenario, deployer: Any, mw: MarkovWorld, *, where: str = "", guard: Any = None) -> None:
        self.mw = mw
        #: where a crash can be replayed ("": desmon verify, which runs the model as declared)
        self.where = where or "desmon verify shows the path to it"
        # the checker's bounds without its budgets, and no scripted first action: the
        # chain starts before the monitor has recognised anything
        plain = replace(scenario, timeline=())
        self.system = TransitionSystem(plain, deployer, invariants=(), bounds=chain_bounds(scenario, mw), guard=guard)
        self.model = scenario.model
        self.rules = ControlRules(self.model)
        # (key, event, physical facts where they differ or None) -> the reaction's outcomes
        self._react_memo: dict[tuple[Key, Event, tuple | None], list[tuple[float, Key, tuple, tuple[str, ...]]]] = {}
        self._lease_memo: dict[tuple[Key, str, tuple[str, ...]], str | None] = {}
        self._physical_memo: dict[tuple, Callable[[str, str], str | None]] = {}
        self._tried: dict[tuple[Key, Event], frozenset[tuple[str, str]]] = {}
        self._wires: dict[tuple[str, str], tuple[tuple[str, ...], ...]] = {}
        self._hosts = {d.name: d.platform for d in scenario.model.devices}
        self.leased = dict(mw.lease)  # on-demand platform -> mean start-up
        self.reactions = 0
        self.faults = tuple((c, k, 1.0 / f, 1.0 / r) for c, k, f, r in mw.faults)  # k: "device" or "platform"
        self.event = WorldEvents(self.system.bounds, mw)
        self.latency = {p.name: mw.latency_of(p.name) for p in self.model.platforms}
        self.warm = dict(mw.warmup)  # graph -> mean warm-up s

    # -- reactions -----------------------------------------------------------------------
    def react(self, key: Key, event: Event, world: tuple | None = None) -> list[tuple[float, Key, tuple, tuple[str, ...]]]:
        """(probability, next key, commands, graphs with no acceptable platform) of each
        outcome of ``event`` on ``key``: the real reaction, every start a coin of
        ``start_failure_p``. ``world``: the physically (failed devices, down platforms)
        where they differ from what ``key`` knows; the Control rules judge a start on
        them, as in the simulation: one they refuse (its platform or inputs gone) fails
        there and is no coin, one they allow is a coin even where the repository believes
        its platform down."""
        known = self._react_memo.get((key, event, None))
        if known is None:
            known = self._react(key, event, None)
        if world is None:
            return known
        # the physical facts change the reaction only if they judge a start it tries
        # otherwise than the known ones (refuse what they allow, or allow what they refuse):
        # up to such a start both runs see the same answers (the rules read the graph's
        # requirements after the event: the store is loaded with an outcome's key)
        physical = self._physical_memo.get(world) or self._physical_memo.setdefault(world, _physical(self.model, self.system.store.rules, *world))
        tried = self._tried[(key, event)]
        if not tried:
            return known
        store = self.system.store
        store.load(known[0][1] if known else key)
        if all((physical(g, pl) is None) == (store.rules.start_refusal(g, pl, store.platform_state) is None) for g, pl in tried):
            return known
        out = self._react_memo.get((key, event, world))
        return out if out is not None else self._react(key, event, world, physical)

    def _react(self, key: Key, event: Event, world: tuple | None, physical: Callable[[str, str], str | None] | None = None) -> list:
        out: list = []
        store = self.system.store
        store.physical = physical
        try:
            tried = self._run_outcomes(key, event, self.mw.start_failure_p, [()], out)
        finally:
            store.physical = None
        if world is None:
            self._tried[(key, event)] = tried
        self._react_memo[(key, event, world)] = out
        return out

    def _run_outcomes(self, key: Key, event: Event, p: float, pending: list, out: list) -> frozenset[tuple[str, str]]:
        """Run every outcome of the reaction into ``out``; the (graph, platform) of every
        start it tried."""
        tried: set[tuple[str, str]] = set()
        while pending:
            prefix = pending.pop()
            first = self.system.run_one(key, event, prefix)
            nkey, outcomes, log, instant = first
            self.reactions += 1
            crash = crash_of(instant)
            if crash is not None:  # exit 4, as desmon verify's CRASHED
                raise DeployerFault(
                    f"deployer {self.system.deployer_name} crashed reacting to {event} in a state the chain reached: {crash[1]}; "
                    f"{self.where} (a crashing deployer has no exposure to compute)"
                )
            if self.reactions <= RECHECK_FIRST or not self.reactions % RECHECK_EVERY:  # desmon verify's nondeterminism check
                same_again(self.system, key, event, prefix, first)
            nf = outcomes.count(False)
            prob = (p ** nf) * ((1.0 - p) ** (len(outcomes) - nf)) if p > 0 else 1.0
            if p > 0:
                for i in range(len(prefix), len(outcomes)):
                    pending.append(outcomes[:i] + (False,))
            tried.update((c.graph, c.platform) for c, _ok in log.commands if type(c) is Start)
            cmds = tuple((type(c) is Start, c.graph, c.platform) for c, ok in log.commands if ok and isinstance(c, (Start, Stop)))
            homeless = tuple(c.graph for c, _ok in log.commands if isinstance(c, RaiseError) and c.kind == NO_ACCEPTABLE_PLATFORMS)
            if prob > 0:
                out.append((prob, nkey, cmds, homeless))
        return frozenset(tried)

    def _starting_after(self, s: ChainState, cmds: tuple, nkey: Key) -> ChainState:
        """``s`` with ``nkey`` and the detectors still starting or warming up after a
        reaction's successful starts and stops (a start with no latency warms up at once)."""
        if not cmds and nkey.deployments == s.key.deployments and _unchanged_by(s, nkey.deployments):
            return s._replace(key=nkey)  # most reactions start and stop nothing: what starts and warms stays
        deployed = set(s.key.deployments)
        starting = set(s.starting)
        warming = {(g, p): k for g, p, k in s.warming}
        for is_start, g, p in cmds:
            pair = (g, p)
            if is_start:
                if pair not in deployed:
                    deployed.add(pair)
                    if self.latency.get(p, 0.0) > 0:
                        starting.add(pair)
                    elif self.warm.get(g, 0.0) > 0 and self._inputs_up(s, g, p):
                        warming[pair] = 0
            else:
                deployed.discard(pair)
                starting.discard(pair)
                warming.pop(pair, None)
        live = set(nkey.deployments)
        busy = {p for _g, p in live}
        return s._replace(
            key=nkey, starting=tuple(sorted(starting & live)),
            warming=tuple(sorted((g, p, k) for (g, p), k in warming.items() if (g, p) in live)),
            idle=tuple((p, k) for p, k in s.idle if p not in busy),  # hosting again: its idle time starts over
        )

    def _wiring(self, g: str, p: str) -> tuple[tuple[str, ...], ...]:
        """The devices ``g`` reads on ``p``, per device kind (the simulation's wiring)."""
        w = self._wires.get((g, p))
        if w is None:
            w = self._wires[(g, p)] = tuple(tuple(d.name for d in devs) for _k, devs in self.rules.input_devices(g, p))
        return w

    def _inputs_up(self, s: ChainState, g: str, p: str) -> bool:
        """``g`` on ``p`` runs physically with every input readable in ``s``."""
        if p in s.phys_down:
            return False
        hosts = self._hosts
        return all(any(d not in s.phys_failed and hosts[d] not in s.phys_down for d in devs) for devs in self._wiring(g, p))

    def _rewarm(self, before: ChainState, after: ChainState) -> ChainState:
        """``after`` a physical change: a deployed, started detector whose platform or
        inputs came back warms up again from its first phase (the simulation re-activates
        it); one that lost them stops warming (it warms again when they return)."""
        if not self.warm:
            return after
        warming = {(g, p): k for g, p, k in after.warming}
        starting = set(after.starting)
        changed = False
        for g, p in after.key.deployments:
            if (g, p) in starting or self.warm.get(g, 0.0) <= 0:
                continue
            was, now = self._inputs_up(before, g, p), self._inputs_up(after, g, p)
            if now and not was:
                warming[(g, p)] = 0
                changed = True
            elif was and not now and (g, p) in warming:
                del warming[(g, p)]
                changed = True
        if not changed:
            return after
        return after._replace(warming=tuple(sorted((g, p, k) for (g, p), k in warming.items())))

    # -- transitions -----------------------------------------------------------------------
    def transitions(self, s: ChainState) -> Iterator[tuple[float, ChainState]]:
        """(rate, next state) of every transition out of ``s``."""
        for rate, _event, outcomes in self.slots(s):
            for prob, t, _cmds in outcomes:
                yield rate * prob, t

    def slots(self, s: ChainState) -> Iterator[Slot]:
        """Every race out of ``s``: (rate, the event the deployer reacts to or None, its
        outcomes as (probability, next state, successful starts and stops)), in one
        fixed order (the MDP of :mod:`desmon.analyze.mdp` lines up the slots of several
        deployers by it)."""
        mw = self.mw
        yield from self._task(s)
        if mw.recognition_delay > 0:
            ctx = recognised(mw.steps[s.pos][0])
            if ctx != s.key.context:
                yield self._deliver(s, self.event("action", None, ctx), 1.0 / mw.recognition_delay)
        yield from self._faults(s)
        for pair in s.starting:
            lat = self.latency[pair[1]]
            ready = s._replace(starting=tuple(x for x in s.starting if x != pair))
            g, p = pair
            if self.warm.get(g, 0.0) > 0 and self._inputs_up(s, g, p):  # ready: its warm-up begins
                ready = ready._replace(warming=tuple(sorted((*s.warming, (g, p, 0)))))
            yield 1.0 / lat, None, ((1.0, ready, ()),)
        for entry in s.warming:
            g, p, k = entry
            rest = tuple(x for x in s.warming if x != entry)
            nxt = rest if k + 1 >= mw.phases else tuple(sorted((*rest, (g, p, k + 1))))
            yield mw.phases / self.warm[g], None, ((1.0, s._replace(warming=nxt), ()),)
        for change, rate in mw.changes:
            yield self._deliver(s, change, rate)
        yield from self._loads(s)
        if self.leased:
            yield from self._lease(s)
        for event, rate, moved in self.event.timed(s):  # the variables of other kinds
            yield self._deliver(self._rewarm(s, moved), event, rate)

    def _deliver(self, s: ChainState, event: Event, rate: float) -> Slot:
        key = s.key
        same = s.phys_failed == key.failed and s.phys_down == key.down
        outcomes = tuple(
            (prob, self._requesting(self._starting_after(s, cmds, nkey), homeless), cmds)
            for prob, nkey, cmds, homeless in self.react(key, event, None if same else (s.phys_failed, s.phys_down))
        )
        return rate, event, outcomes

    def _requesting(self, s: ChainState, homeless: tuple[str, ...]) -> ChainState:
        """``s`` after the lease has answered each graph the reaction found no platform
        for: the simulation's choice among the absent platforms not yet on their way."""
        if not homeless or not self.leased:
            return s
        requested = set(s.requested)
        for g in homeless:
            absent = tuple(p for p in self.leased if p in s.phys_down and p not in requested)
            if not absent:
                break
            mk = (s.key, g, absent)
            if mk not in self._lease_memo:
                store = self.system.store
                store.load(s.key)
                self._lease_memo[mk] = lease_choice(store, g, absent)
            choice = self._lease_memo[mk]
            if choice is not None:
                requested.add(choice)
        return s._replace(requested=tuple(sorted(requested)))

    def _loads(self, s: ChainState) -> Iterator[Slot]:
        """A load step to each neighbouring level."""
        loads = dict(s.key.loads)
        for p, r, levels, rate in self.mw.loads:
            i = levels.index(dict(loads.get(p, ())).get(r, 0))
            nbrs = [levels[j] for j in (i - 1, i + 1) if 0 <= j < len(levels)]
            for level in nbrs:
                yield self._deliver(s, self.event("load", p, level), rate / len(nbrs))

    def _lease(self, s: ChainState) -> Iterator[Slot]:
        """Leased platforms joining, leaving after an idle time (Erlang-``phases``, its
        phases counted only while the platform hosts nothing), and the monitor noticing it."""
        hb = self.mw.heartbeat_timeout
        busy = {p for _g, p in s.key.deployments}
        idle = dict(s.idle)
        for p, startup in self.leased.items():
            absent = p in s.phys_down
            flip = None
            if absent and p in s.requested:
                flip = (1.0 / startup, s._replace(requested=tuple(x for x in s.requested if x != p), phys_down=tuple(x for x in s.phys_down if x != p)))
            elif not absent and p not in busy:
                rate = self.mw.phases / self.mw.lease_idle_s
                k = idle.get(p, 0) + 1
                rest = tuple(x for x in s.idle if x[0] != p)
                if k < self.mw.phases:  # one more phase of idle time: nothing happens yet
                    yield rate, None, ((1.0, s._replace(idle=tuple(sorted((*rest, (p, k))))), ()),)
                else:
                    flip = (rate, s._replace(phys_down=tuple(sorted((*s.phys_down, p))), idle=rest))
            if flip is not None:
                rate, ns = flip
                ns = self._rewarm(s, ns)
                yield (rate, None, ((1.0, ns, ()),)) if hb > 0 else self._deliver(ns, self.event("join", p, not absent), rate)
            if hb > 0 and absent != (p in s.key.down):
                yield self._deliver(s, self.event("join", p, absent), 1.0 / hb)

    def _task(self, s: ChainState) -> Iterator[Slot]:
        mw = self.mw
        rate = mw.phases / mw.steps[s.pos][1]
        if s.phase + 1 < mw.phases:
            yield rate, None, ((1.0, s._replace(phase=s.phase + 1), ()),)
            return
        nxt = s._replace(pos=(s.pos + 1) % len(mw.steps), phase=0)
        if mw.recognition_delay > 0:
            yield rate, None, ((1.0, nxt, ()),)
        else:
            yield self._deliver(nxt, self.event("action", None, recognised(mw.steps[nxt.pos][0])), rate)

    def _faults(self, s: ChainState) -> Iterator[Slot]:
        hb = self.mw.heartbeat_timeout
        known_failed, known_down = set(s.key.failed), set(s.key.down)
        for c, kind, fail, repair in self.faults:
            is_dev = kind == "device"
            phys = s.phys_failed if is_dev else s.phys_down
            broken = c in phys
            flipped = tuple(sorted(set(phys) - {c})) if broken else tuple(sorted((*phys, c)))
            ns = self._rewarm(s, s._replace(phys_failed=flipped) if is_dev else s._replace(phys_down=flipped))
            rate = repair if broken else fail
            if hb > 0:
                yield rate, None, ((1.0, ns, ()),)
            else:
                yield self._deliver(ns, self.event(kind, c, not broken), rate)
            if hb > 0 and broken != (c in (known_failed if is_dev else known_down)):
                yield self._deliver(s, self.event(kind, c, broken), 1.0 / hb)


class WorldEvents:
    """The checker events of the chain's world. Called with (kind, subject, value): the
    event that moves the ``kind`` variable of ``subject`` to ``value``
    (:meth:`~desmon.verify.environment.VariableKind.event_to`), one object per event: a
    task step, a fault, a load step or a lease made a checker event. :meth:`timed`: the
    moves of the variables of the kinds the chain times by their rates."""

    def __init__(self, bounds: Any, mw: MarkovWorld) -> None:
        self.bounds = bounds
        self._memo: dict[tuple[str, Any, Any], Event] = {}
        #: (kind, subject, event -> rate) of each variable timed by its kind's rates
        self.variables = tuple((variable_kind(k), subject, dict(rates)) for k, subject, rates in mw.timed)

    def __call__(self, kind: str, subject: Any, value: Any) -> Event:
        k = (kind, subject, value)
        e = self._memo.get(k)
        if e is None:
            e = self._memo[k] = variable_kind(kind).event_to(self.bounds, subject, value)  # type: ignore[union-attr]
        return e

    def timed(self, s: ChainState) -> Iterator[tuple[Event, float, ChainState]]:
        """(event, rate, ``s`` with the world moved by it) of each event the timed
        variables enable in ``s`` (:meth:`~desmon.verify.environment.VariableKind.rates`):
        in the world and known at once, with no failure budget (``room``)."""
        for kind, subject, rates in self.variables:
            for event in kind.enabled(self.bounds, s.key, subject, True):
                rate = rates.get(event)
                if rate:
                    yield event, rate, _physically(s, event)


def _physically(s: ChainState, event: Event) -> ChainState:
    """``s`` with the world moved by ``event`` (a device that stops or starts working, a
    platform that goes down or comes up; any other event moves only what is known)."""
    if isinstance(event, DeviceEvent):
        failed = set(s.phys_failed) - {event.device} if event.working else set(s.phys_failed) | {event.device}
        return s._replace(phys_failed=tuple(sorted(failed)))
    if isinstance(event, PlatformEvent):
        down = set(s.phys_down) - {event.platform} if event.up else set(s.phys_down) | {event.platform}
        return s._replace(phys_down=tuple(sorted(down)))
    return s


def build_chain(
    scenario: Scenario, deployer: Any, mw: MarkovWorld, *, max_states: int | None = None,
    progress: Callable[[int], None] | None = None, miss: dict[str, Any] | None = None,
    start_catch: dict[str, Any] | None = None, guard: Any = None, budget: Callable[[], None] = no_budget,
    detection: Callable[[], tuple[dict[str, Any], dict[str, Any]]] | None = None,
) -> Chain:
    """Every chain state reachable from the initial ones, with its rates and rewards;
    ``miss`` is each graph's probability of missing a slip while it watches (1 where
    not given), ``start_catch`` of catching one while it starts (graph -> action ->
    start latency -> p; 0 where not given); ``detection()``, if given, returns both
    instead, called once every state is found (a deployer that crashes, or a chain past
    ``max_states``, ends the build before its detection trials run; their time is not
    counted in ``build_s``); ``guard``: the run's guard around the deployer
    (:mod:`desmon.deployment.guard`); ``budget()`` raises :class:`BudgetExceeded` once the
    time or memory budget is spent (:class:`~desmon.analyze.markov.Budget`)."""
    t0 = time.perf_counter()
    b = Builder(scenario, deployer, mw, guard=guard)
    try:
        key0 = b.system.initial()
    except CheckerError as exc:
        raise AnalysisError(str(exc)) from None
    s0 = ChainState(key0, 0, 0, tuple(sorted(key0.failed)), tuple(sorted(key0.down)), ())  # what fails at the start is physically failed
    start = [(1.0, s0)]
    if mw.recognition_delay == 0:  # the monitor sees the first step at once: its reaction's outcomes
        start = [(p, t) for p, t, _c in b._deliver(s0, b.event("action", None, recognised(mw.steps[0][0])), 1.0)[2]]
    index: dict[ChainState, int] = {}
    states: list[ChainState] = []
    initial: dict[int, float] = {}
    for prob, s in start:
        j = index.setdefault(s, len(states))
        if j == len(states):
            states.append(s)
        initial[j] = initial.get(j, 0.0) + prob
    # compact typed arrays: a million-state chain has about ten million transitions
    rows, cols, rates = array("q"), array("q"), array("d")
    i = 0
    while i < len(states):
        s = states[i]
        merged: dict[int, float] = {}
        for rate, t in b.transitions(s):
            j = index.get(t)
            if j is None:
                j = index[t] = len(states)
                states.append(t)
                if max_states is not None and len(states) > max_states:
                    raise BudgetExceeded(f"the chain has more than --max-states {max_states} states: raise it, or analyze fewer faults")
            if j != i:
                merged[j] = merged.get(j, 0.0) + rate
        for j, r in merged.items():
            rows.append(i)
            cols.append(j)
            rates.append(r)
        i += 1
        if not i % 256:
            budget()
        if progress is not None and not i % 5000:
            progress(i)
    chain = Chain(states, np.frombuffer(rows, dtype=np.int64), np.frombuffer(cols, dtype=np.int64), np.frombuffer(rates, dtype=float), mw, b.system)
    chain.initial = tuple(sorted(initial.items()))
    trials_s = 0.0
    if detection is not None:
        t1 = time.perf_counter()
        miss, start_catch = detection()
        trials_s = time.perf_counter() - t1
    rewards(chain, b.rules, dict(miss or {}), dict(start_catch or {}))
    chain.build_s = time.perf_counter() - t0 - trials_s
    chain.trials_s = trials_s
    chain.reactions = b.reactions
    check_module_state(b.system)  # (a user's deployer: refused if its module kept state between reactions, as desmon verify refuses it)
    return chain


def _member_states(
    s: Any, blind: set[str], hosts: dict[str, str], inputs: Callable[[str, str], tuple]
) -> tuple[dict[str, list[str]], set[tuple[str, str]]]:
    """The state of every deployed instance in chain state ``s``, per graph (one of
    :data:`~desmon.deployment.exposure.MEMBER_STATES`), in the order the simulation's
    :meth:`~desmon.sim.facts.PhysicalFacts.member_state` asks: an instance on a platform that is
    down, or whose input has no readable device, has lost its input, starting or not; and
    the (graph, platform) of the instances that are starting (in their start latency or
    warm-up) on a live platform."""
    warming = {(g, p) for g, p, _k in s.warming}
    state: dict[str, list[str]] = {}
    starting: set[tuple[str, str]] = set()
    for g, p in s.key.deployments:
        if p in s.phys_down or not all(any(d not in s.phys_failed and hosts[d] not in s.phys_down for d in devs) for devs in inputs(g, p)):
            st = "input_lost"
        elif g in blind:
            st = "cannot_detect"
        elif (g, p) in s.starting or (g, p) in warming:
            st = "starting"
            starting.add((g, p))
        else:
            st = WATCHING
        state.setdefault(g, []).append(st)
    return state, starting


def start_catch_of(mw: Any, g: str, starting: set[tuple[str, str]], catch: dict[float, float]) -> float:
    """The probability that graph ``g``, starting or warming up (``starting``: its instances
    that are, on live platforms, from :func:`_member_states`), catches a slip that begins now:
    ``catch`` by the start latency of its platform
    (:func:`~desmon.analyze.measures.detector_start_catch`), the best of its instances. An
    instance on a platform that went down, or without its input, raises no alarm."""
    best = 0.0
    for dg, p in starting:
        if dg == g:
            best = max(best, catch.get(mw.latency_of(p), 0.0))
    return best


def rewards(chain: Chain, rules: ControlRules, miss: dict[str, Any], start_catch: dict[str, Any] | None = None) -> None:
    """The labels of every state by the one definition of :mod:`desmon.deployment.exposure`
    (unmonitored, by cause; risky; excluded) and its undetected-slip rate: slips arrive
    at ``slip_rate`` while an object is in the hand, and each watching detector misses
    one with its probability for the action (``miss[graph]``: a number, or action ->
    number)."""
    model = chain.system.model
    mw = chain.world
    table = needs_table(model)
    blind = set(mw.blind)
    n = chain.n
    unmon = np.zeros(n)
    risky = np.zeros(n)
    excluded = np.zeros(n)
    undetected = np.zeros(n)
    by_cause = {c: np.zeros(n) for c in CAUSES}
    wiring: dict[tuple[str, str], tuple] = {}
    hosts = {d.name: d.platform for d in model.devices}
    catching = start_catch or {}

    def inputs(g: str, p: str) -> tuple:  # the alternative devices of each input of g on p
        w = wiring.get((g, p))
        if w is None:
            w = wiring[(g, p)] = tuple(tuple(d.name for d in devs) for _k, devs in rules.input_devices(g, p))
        return w

    for i, s in enumerate(chain.states):
        action = mw.steps[s.pos][0]
        need = table[action]
        if not need.risky:
            continue
        risky[i] = 1.0
        if need.excluded:
            excluded[i] = 1.0
        state, starting = _member_states(s, blind, hosts, inputs)
        why = cause(need, lambda g: best_state(state.get(g, ())))
        if why is not None:
            unmon[i] = 1.0
            by_cause[why][i] = 1.0
        # a slip in the hand goes undetected unless a watching detector catches it, or one
        # still starting or warming up alarms in its window (start_catch_of)
        m = 1.0
        for g, sts in state.items():
            mg = miss.get(g, 1.0)
            mg = mg.get(action, 1.0) if isinstance(mg, dict) else mg
            if WATCHING in sts:
                m *= mg
            elif "starting" in sts and g in catching:
                m *= 1.0 - start_catch_of(mw, g, starting, catching[g].get(action, {}))
        undetected[i] = mw.slip_rate * m
    chain.unmonitored, chain.risky, chain.undetected = unmon, risky, undetected
    chain.causes, chain.excluded = by_cause, excluded
