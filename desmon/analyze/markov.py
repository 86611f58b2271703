"""The Markov world: a scenario's World read as rates, matched against its checker bounds.

The chain (:mod:`desmon.analyze.chain`) lets the environment do what the scenario's
:class:`~desmon.verify.bounds.Bounds` let the checker do, at the rates the scenario's
:class:`~desmon.sim.world.World` gives:

* the robot's task is a repeating cycle of its steps; each step lasts an exponential
  time with the step's duration as mean, or an Erlang-``phases`` time (``--phases k``:
  k exponential phases of mean duration/k each, closer to a fixed duration);
* each component of ``World.stochastic_faults`` fails after an exponential time of
  mean MTTF and is repaired after one of mean MTTR;
* the context monitor recognises a new action after an exponential delay of mean
  ``recognition_delay`` and notices a failure or repair after one of mean
  ``heartbeat_timeout`` (0: at once); it then reports what the world is like *then*;
* a started detector is ready after an exponential start latency of mean
  ``start_latency`` (or the platform's own); a start fails with probability
  ``start_failure_p`` (default ``World.start_failure.probability``), decided at once;
* once ready, and again whenever its platform comes back or a lost input returns, a
  detector warms up (the force detector re-tares 0.5 s, the tactile one waits three
  frames: its signal model's warm-up) for an Erlang-``phases`` time of that mean, as
  the task steps; it watches only after that;
* random requirement changes (``World.random_changes``) arrive at rate
  1/``mean_interval``, each change equally likely;
* slips arrive at ``World.slip_rate`` per second of object-in-hand time;
* a load walk over levels (``World.load_steps``) moves to a neighbouring level at
  rate 1/``mean_interval``, split evenly over the neighbours; the repository learns
  the new load at once;
* with ``World.lease``, a reaction that raises *no acceptable platform* for a graph
  requests the on-demand platform :func:`~desmon.deployment.lease.lease_choice` names
  (the simulation's own choice); it joins after an exponential start-up of mean its
  ``startup_s``, and leaves at rate 1/``idle_s`` while it hosts nothing;
* the variables of any other kind (one that is not
  :attr:`~desmon.verify.environment.VariableKind.timed_by_chain`) move by their
  kind's :meth:`~desmon.verify.environment.VariableKind.rates`: each event at its rate
  whenever the state enables it, in the world and known to the repository at once.

Every event the bounds let the checker choose needs a rate here (each kind of variable
names what gives its events one: :attr:`desmon.verify.environment.VariableKind.rate`),
and every rate an event there: :func:`markov_world` refuses a mismatch in one line naming it (a fault
without MTTF, an MTTF of a component the checker never fails, scripted faults, loads
or changes, which have no rate; a Gaussian load walk). The bounds' ``max_failures`` and ``start_failures``
are budgets of the checker, not facts of the world: the chain drops them (any number
of components may be down at once; any start may fail), and says so
(:attr:`MarkovWorld.dropped`).
"""

from __future__ import annotations

import math
import resource
import time
from dataclasses import dataclass, replace
from typing import Any, Callable

from desmon.errors import DesmonError
from desmon.model.checks import check_number
from desmon.model.events import Event, LoadChange, RequirementChange
from desmon.model.scenario import Scenario
from desmon.sim.world import World, can_detect, detector_plans, world_of
from desmon.verify.bounds import Bounds, bounds_of
from desmon.verify.environment import VariableKind, variable_kind, variables

__all__ = ["AnalysisError", "MarkovWorld", "markov_world", "world_phases", "MAX_PHASES", "RATE_RATIO", "check_rates", "named_rates", "BudgetExceeded", "Budget", "no_budget"]

#: the most Erlang phases a task step may take (``--phases``)
MAX_PHASES = 64


class AnalysisError(DesmonError, ValueError):
    """The analysis cannot run as asked (a rate without an event, a bad horizon, ...)."""


class BudgetExceeded(AnalysisError):
    """The chain grew past ``--max-states``, or the work past ``--timeout`` or ``--max-memory`` (exit 3)."""


#: seconds between two looks at the resident memory (``--max-memory``)
MEMORY_EVERY = 0.5


class Budget:
    """``--timeout`` (seconds from ``started``, a ``time.perf_counter`` value) and
    ``--max-memory`` (MB of peak resident memory) of one analysis: calling it raises
    :class:`BudgetExceeded` once either is spent. The chain's construction and every
    solver loop call it, so no step runs on past the budget by more than one of its
    iterations (a sparse factorisation, a library call, is one)."""

    def __init__(self, timeout: float | None = None, max_memory: float | None = None, started: float | None = None) -> None:
        self.timeout, self.max_memory = timeout, max_memory
        t0 = time.perf_counter() if started is None else started
        self.deadline = math.inf if timeout is None else t0 + timeout
        self._next_look = 0.0

    def __call__(self, *_ignored: Any) -> None:
        now = time.perf_counter()
        if now > self.deadline:
            raise BudgetExceeded(f"timeout {self.timeout:g}s reached before the analysis ended: raise --timeout, or analyze a smaller chain")
        if self.max_memory is not None and now >= self._next_look:
            self._next_look = now + MEMORY_EVERY
            mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
            if mb > self.max_memory:
                raise BudgetExceeded(f"memory budget {self.max_memory:g} MB reached: {mb:,.0f} MB resident; raise --max-memory, or analyze a smaller chain")


    def within(self, work: Callable[[], Any], what: str) -> Any:
        """``work()``, a library call this budget cannot interrupt between its steps (Storm's
        solvers): where a ``--timeout`` is set, run in a forked process that is killed once the
        time is spent (:class:`BudgetExceeded`); its result comes back pickled. ``what``
        names it in the refusal."""
        if self.deadline == math.inf:
            return work()
        import os
        import pickle
        import select
        import signal

        read, write = os.pipe()
        pid = os.fork()
        if pid == 0:  # pragma: no cover - the child
            os.close(read)
            try:
                data = pickle.dumps(("ok", work()))
            except BaseException as exc:  # its error, raised again in desmon's process
                data = pickle.dumps(("error", AnalysisError(f"{what}: {type(exc).__name__}: {' '.join(str(exc).split())[:300]}")))
            with os.fdopen(write, "wb") as fh:
                fh.write(data)
            os._exit(0)
        os.close(write)
        chunks: list[bytes] = []
        try:
            while True:
                left = self.deadline - time.perf_counter()
                if left <= 0 or not select.select([read], [], [], left)[0]:
                    os.kill(pid, signal.SIGKILL)
                    raise BudgetExceeded(f"timeout {self.timeout:g}s reached while {what} ran: raise --timeout, or analyze a smaller chain")
                chunk = os.read(read, 1 << 20)
                if not chunk:
                    break
                chunks.append(chunk)
        finally:
            os.close(read)
            os.waitpid(pid, 0)
        if not chunks:
            raise AnalysisError(f"{what} ended without a result")
        kind, value = pickle.loads(b"".join(chunks))
        if kind == "error":
            raise value
        return value


def no_budget(*_ignored: Any) -> None:
    """The budget of an analysis without one."""


@dataclass(frozen=True)
class MarkovWorld:
    """The rates of the chain, all in events per second (0: the event never happens)."""

    #: (action, mean duration s) of each task step, in cycle order
    steps: tuple[tuple[str, float], ...]
    phases: int
    #: (component, "device" | "platform", mttf s, mttr s)
    faults: tuple[tuple[str, str, float, float], ...]
    #: mean start latency per platform (s; 0: ready at once)
    latency: tuple[tuple[str, float], ...]
    recognition_delay: float
    heartbeat_timeout: float
    start_failure_p: float
    slip_rate: float
    #: (change, rate) of each random requirement change
    changes: tuple[tuple[RequirementChange, float], ...]
    #: the checker's budgets the chain drops, as (field, value) pairs
    dropped: tuple[tuple[str, Any], ...] = ()
    #: (platform, resource, levels, rate of a step) of each load walk over levels
    loads: tuple[tuple[str, str, tuple[float, ...], float], ...] = ()
    #: (on-demand platform, mean start-up s) of each platform the lease may join
    lease: tuple[tuple[str, float], ...] = ()
    #: mean seconds a leased platform stays once it hosts nothing (0: no lease)
    lease_idle_s: float = 0.0
    #: (graph, mean warm-up s) of every graph that warms up after an activation
    warmup: tuple[tuple[str, float], ...] = ()
    #: graphs that cannot detect a slip (an input without a signal model): never watching
    blind: tuple[str, ...] = ()
    #: (kind, subject, ((event, rate), ...)) of each variable the chain times by its kind's rates
    timed: tuple[tuple[str, Any, tuple[tuple[Event, float], ...]], ...] = ()

    def latency_of(self, platform: str) -> float:
        return dict(self.latency).get(platform, 0.0)

    def to_json(self) -> dict[str, Any]:
        """The rates used, as ``desmon analyze --json`` writes them (per second)."""
        out = {
            "task_steps": [{"action": a, "mean_s": d, "rate_per_s": 1.0 / d} for a, d in self.steps],
            "phases": self.phases,
            "faults": [
                {"component": c, "kind": k, "mttf_s": f, "mttr_s": r, "fail_rate_per_s": 1.0 / f, "repair_rate_per_s": 1.0 / r}
                for c, k, f, r in self.faults
            ],
            "start_latency_s": dict(self.latency),
            "recognition_delay_s": self.recognition_delay,
            "heartbeat_timeout_s": self.heartbeat_timeout,
            "start_failure_p": self.start_failure_p,
            "slip_rate_per_s": self.slip_rate,
            "warm_up_s": dict(self.warmup),
            "cannot_detect": list(self.blind),
            "requirement_changes": [{"change": c.label or str(c), "rate_per_s": r} for c, r in self.changes],
            "dropped_checker_budgets": dict(self.dropped),
            "load_steps": [
                {"platform": p, "resource": r, "levels": list(lv), "rate_per_s": rate} for p, r, lv, rate in self.loads
            ],
            "lease": {
                "platforms": [{"platform": p, "startup_s": t, "join_rate_per_s": 1.0 / t} for p, t in self.lease],
                "idle_s": self.lease_idle_s,
                "leave_rate_per_s_while_idle": 1.0 / self.lease_idle_s if self.lease_idle_s else 0.0,
                "idle_phases": self.phases,
            },
        }
        if self.timed:
            out["timed_variables"] = [
                {"kind": k, "subject": str(subject), "events": [{"event": str(e), "rate_per_s": r} for e, r in rates]}
                for k, subject, rates in self.timed
            ]
        return out


def _refuse(scenario: Scenario, msg: str) -> AnalysisError:
    return AnalysisError(f"scenario {scenario.name!r}: {msg}")


def _check_unrated(scenario: Scenario, world: World) -> None:
    """Scripted parts of the world have times, not rates."""
    first_fault = next((getattr(te.event, "device", None) or getattr(te.event, "platform", None) for te in world.faults), None)
    scripted = [
        ("faults", world.faults, f"stochastic_faults=(MTTF({first_fault or 'lwr_wrench'!r}, mttf=3600, mttr=120),) or the like"),
        ("loads", world.loads, "no scripted loads"),
        ("changes", world.changes, "random_changes=RandomChanges(...)"),
    ]
    for field_, events, fix in scripted:
        if events:
            first = events[0]
            raise _refuse(
                scenario,
                f"World {field_} are scripted ({first.event} at {first.time:g} s): a Markov chain needs rates, not times; "
                f"give {fix} instead (a scenario may offer a stochastic variant as a parameter, -p)",
            )
    if world.load_walks:
        w = world.load_walks[0]
        raise _refuse(
            scenario,
            f"World load walk of {w.platform!r} is a Gaussian walk with no rate per load level: give "
            f"load_steps=(LoadSteps({w.platform!r}, levels=..., start=..., mean_interval=...),) instead (the bounds' load levels)",
        )
    if world.start_failure.script:
        g, p, n = world.start_failure.script[0]
        raise _refuse(scenario, f"World start failure script ({g} on {p}, attempt {n}) is scripted: give StartFailure(probability=...) instead")
    if world.slips:
        raise _refuse(
            scenario,
            f"World slips are scripted (a slip at {world.slips[0].time:g} s): a Markov chain counts slips by their rate, and "
            "would leave these out of its undetected slips; give slip_rate=... (slips per second of object-in-hand time) instead",
        )


def _check_variables(scenario: Scenario, world: World, b: Bounds) -> None:
    """Every variable of the bounds has a kind that names what gives its events a rate,
    and a kind the chain does not time itself gives them rates."""
    for v in variables(b):
        kind = variable_kind(v.kind)
        if kind is None or kind.rate is None:
            raise _refuse(
                scenario,
                f"the checker bounds let the {v.kind} variable {v.subject!r} change, but nothing gives its events a rate "
                f"(its kind of variable names none): drop it from the bounds' variables to analyze the rest",
            )
        if not kind.timed_by_chain and not _rates(kind, world, b, v.subject):
            raise _refuse(
                scenario,
                f"the checker bounds let the {v.kind} variable {v.subject!r} change, but its kind of variable gives its events "
                f"no rates ({kind.rate}): give them rates, or drop it from the bounds' variables to analyze the rest",
            )


def _check_matching(scenario: Scenario, world: World, b: Bounds) -> None:
    """An event of the bounds without a rate, or a rate without an event: one line."""
    _check_variables(scenario, world, b)
    rated = {m.component for m in world.stochastic_faults}
    for what, names in (("device", b.devices), ("platform", b.platforms)):
        for n in names:
            if n not in rated:
                verb = "fail" if what == "device" else "go down"
                raise _refuse(
                    scenario,
                    f"the checker bounds let {what} {n!r} {verb} but the World gives it no rate: add MTTF({n!r}, mttf=..., mttr=...) "
                    f"to World.stochastic_faults, or drop {n!r} from the bounds' {what}s",
                )
    bounded = set(b.devices) | set(b.platforms)
    for m in world.stochastic_faults:
        if m.component not in bounded:
            raise _refuse(
                scenario,
                f"World.stochastic_faults gives {m.component!r} an MTTF but the checker bounds never let it fail: "
                f"add {m.component!r} to the bounds' devices or platforms, or drop its MTTF",
            )
    if world.stochastic_faults and not b.repair:
        raise _refuse(scenario, f"World repairs {world.stochastic_faults[0].component!r} (MTTR) but the checker bounds say repair=False: set repair=True")
    _check_loads(scenario, world, b)
    _check_lease(scenario, world, b)
    random = world.random_changes.changes if world.random_changes is not None else ()
    for c in b.requirement_changes:
        if c not in random:
            raise _refuse(scenario, f"the checker bounds apply requirement change {c.label or c} but World.random_changes gives it no rate: add it there")
    for c in random:
        if c not in b.requirement_changes:
            raise _refuse(scenario, f"World.random_changes makes requirement change {c.label or c} but the checker bounds never apply it: add it to requirement_changes")


def _check_loads(scenario: Scenario, world: World, b: Bounds) -> None:
    """The bounds' load levels and the World's load steps name the same walks."""
    steps = {w.platform: w for w in world.load_steps if w.resource == b.load_resource}
    initial = {ev.platform: ev.amount for ev in scenario.initial if isinstance(ev, LoadChange) and ev.resource == b.load_resource}
    for p, lv in b.loads.items():
        w = steps.get(p)
        if w is None:
            raise _refuse(
                scenario,
                f"the checker bounds move the {b.load_resource} load of {p!r} but the World gives it no rate: add "
                f"LoadSteps({p!r}, levels={tuple(lv)!r}, start=..., mean_interval=...) to World.load_steps, or drop {p!r} from the bounds' loads",
            )
        if tuple(float(x) for x in lv) != w.levels:
            raise _refuse(scenario, f"World load steps of {p!r} move over levels {list(w.levels)} but the checker bounds over {list(lv)}: give both the same levels")
        if float(initial.get(p, 0)) != w.start:
            raise _refuse(
                scenario,
                f"World load steps of {p!r} start at {w.start:g} but the scenario's initial load is {initial.get(p, 0):g}: give them the same value",
            )
    for w in world.load_steps:
        if w.platform not in b.loads or w.resource != b.load_resource:
            raise _refuse(
                scenario,
                f"World load steps move the {w.resource} load of {w.platform!r} but the checker bounds never do: add "
                f"loads={{{w.platform!r}: {w.levels!r}}} (load_resource={w.resource!r}) to the bounds, or drop the load steps",
            )


def _check_lease(scenario: Scenario, world: World, b: Bounds) -> None:
    """Every platform the bounds let join is leased by the World, after a positive start-up."""
    if not b.joins:
        return
    if world.lease is None:
        raise _refuse(
            scenario,
            f"the checker bounds let {b.joins[0]!r} join and leave but the World has no lease, so nothing gives the joins a rate: "
            "add World(lease=Lease(idle_s=...)), or drop joins from the bounds",
        )
    leased = world.lease.platforms or b.joins
    for p in b.joins:
        if p not in leased:
            raise _refuse(scenario, f"the checker bounds let {p!r} join but the World's lease never leases it: add it to Lease(platforms=...)")
        if scenario.model.platform(p).startup_s <= 0:
            raise _refuse(
                scenario,
                f"on-demand platform {p!r} joins at once (startup_s=0), which has no rate: give it a positive startup_s",
            )


def _kind_of(scenario: Scenario, component: str) -> str:
    model = scenario.model
    if component in {d.name for d in model.devices}:
        return "device"
    return "platform"


def _check_arguments(phases: int, start_failure_p: float | None) -> None:
    check_number("--phases", phases, error=AnalysisError, positive=True, integer=True, high=MAX_PHASES)
    if start_failure_p is not None:
        check_number("--start-failure-p", start_failure_p, error=AnalysisError, high=1.0)
        if start_failure_p >= 1.0:
            raise AnalysisError(f"--start-failure-p = {start_failure_p!r}: every start would fail and no detector ever runs; give a probability below 1")


def _start_failure_p(scenario: Scenario, world: World, given: float | None) -> float:
    """The probability a start fails: ``given`` (--start-failure-p, checked by
    :func:`_check_arguments`), else the World's, under the same rule: below 1."""
    p = world.start_failure.probability if given is None else float(given)
    if p >= 1.0:
        raise _refuse(scenario, "its World's StartFailure(probability=1) fails every start, so no detector ever runs; give a probability below 1")
    return p


def _check_cycle(scenario: Scenario, world: World) -> None:
    """The task must repeat (a chain is a cycle) and every step must have a rate."""
    if not world.repeat:
        raise _refuse(
            scenario,
            "World(repeat=False): the task runs once and then nothing happens, which a chain of a repeating cycle would "
            "misstate; give World(repeat=True) to analyze the task as a cycle (desmon run simulates the single pass)",
        )
    for i, step in enumerate(world.task):
        if step.duration <= 0:
            raise _refuse(scenario, f"World task step {i + 1} ({step.action}) lasts 0 s, which has no rate: give it a positive duration")


def world_phases(scenario: Scenario, phases: int | None) -> int:
    """The Erlang phases of a task step in the chain: ``phases`` (``--phases``), else the
    World's where it times its steps so (``timing="exponential", phases=K``), else 1."""
    if phases is not None:
        return phases
    world = scenario.world
    return world.phases if getattr(world, "timing", None) == "exponential" else 1


def markov_world(scenario: Scenario, *, phases: int | None = None, start_failure_p: float | None = None) -> MarkovWorld:
    """The rates of ``scenario``'s World, matched against its checker bounds (see the
    module docstring); :class:`AnalysisError` names the first mismatch. ``phases``:
    :func:`world_phases`."""
    phases = world_phases(scenario, phases)
    _check_arguments(phases, start_failure_p)
    if scenario.world is None:
        raise _refuse(scenario, "it declares no World, so the chain has no rates: give it Scenario(world=World(task=..., stochastic_faults=...))")
    from desmon.sim.fleet import is_fleet

    if is_fleet(scenario):
        raise _refuse(scenario, "a fleet of robots (world is a Fleet); the chain is one robot's: analyze a single-robot "
                                "scenario, or simulate the fleet with desmon run")
    world = world_of(scenario)
    b = replace(bounds_of(scenario), together=False)  # (the chain times one change at a time: no two meet)
    _check_unrated(scenario, world)
    _check_matching(scenario, world, b)
    _check_cycle(scenario, world)
    p = _start_failure_p(scenario, world, start_failure_p)
    plans = detector_plans(world, scenario.model)
    latency = tuple((pl.name, world.latency(pl.name)) for pl in scenario.model.platforms)
    changes: tuple[tuple[RequirementChange, float], ...] = ()
    if world.random_changes is not None:
        rc = world.random_changes
        changes = tuple((c, 1.0 / (rc.mean_interval * len(rc.changes))) for c in rc.changes)
    dropped = []
    if b.max_failures is not None:
        dropped.append(("max_failures", b.max_failures))
    if p > 0 and b.start_failures != math.inf:
        dropped.append(("start_failures", b.start_failures))
    return MarkovWorld(
        steps=tuple((s.action, float(s.duration)) for s in world.task),
        phases=int(phases),
        faults=tuple((m.component, _kind_of(scenario, m.component), m.mttf, m.mttr) for m in world.stochastic_faults),
        latency=latency,
        recognition_delay=world.recognition_delay,
        heartbeat_timeout=world.heartbeat_timeout,
        start_failure_p=p,
        slip_rate=world.slip_rate,
        changes=changes,
        dropped=tuple(dropped),
        loads=tuple((w.platform, w.resource, w.levels, 1.0 / w.mean_interval) for w in world.load_steps),
        lease=tuple((p, scenario.model.platform(p).startup_s) for p in b.joins),
        lease_idle_s=world.lease.idle_s if world.lease is not None and b.joins else 0.0,
        warmup=tuple((g, plan.warmup) for g, plan in plans.items() if plan is not None and plan.warmup > 0),
        blind=tuple(g for g, detects in can_detect(world, plans).items() if not detects),
        timed=_timed_variables(world, b),
    )


def _timed_variables(world: World, b: Bounds) -> tuple[tuple[str, Any, tuple[tuple[Event, float], ...]], ...]:
    """(kind, subject, ((event, rate), ...)) of each variable of a kind the chain does not
    time itself (:func:`_check_variables` has refused one without rates)."""
    out = []
    for v in variables(b):
        kind = variable_kind(v.kind)
        if kind is not None and not kind.timed_by_chain:
            out.append((v.kind, v.subject, tuple((e, float(r)) for e, r in _rates(kind, world, b, v.subject))))
    return tuple(out)


def _rates(kind: VariableKind, world: World, b: Bounds, subject: Any) -> tuple[tuple[Event, float], ...]:
    """The rates ``kind`` gives the events of its variable of ``subject`` (none if it gives none)."""
    try:
        return tuple(kind.rates(world, b, subject))
    except NotImplementedError:
        return ()


def chain_bounds(scenario: Scenario, mw: MarkovWorld) -> Bounds:
    """The checker bounds the chain's transition system runs under: no failure budget,
    every start a choice while ``start_failure_p`` > 0, no initial action (the context
    monitor recognises the task's first step like any other)."""
    b = replace(bounds_of(scenario), together=False)  # (the chain times one change at a time: no two meet)
    return replace(b, max_failures=None, start_failures=10**6 if mw.start_failure_p > 0 else 0, initial_action=None)


def is_rate(x: float) -> bool:
    return math.isfinite(x) and x > 0


#: the widest spread of a chain's rates the solvers take: the fastest rate over the
#: slowest (the horizon counting as a rate of 1/T). Past it the exit rate of a state
#: holds its slow rates to fewer than four of double precision's sixteen digits (at
#: 1e16 they vanish from it), and the transient solution needs about the ratio in steps
RATE_RATIO = 1e12


def named_rates(mw: MarkovWorld, horizon: float) -> list[tuple[float, str]]:
    """(rate per s, what gives it) of every rate of the chain, and the horizon as 1/T."""
    out = [(mw.phases / d, f"World task step {i + 1} ({a}) duration {d:g} s") for i, (a, d) in enumerate(mw.steps)]
    for c, _k, f, r in mw.faults:
        out += [(1.0 / f, f"MTTF of {c!r} {f:g} s"), (1.0 / r, f"MTTR of {c!r} {r:g} s")]
    delays = [("World.recognition_delay", mw.recognition_delay), ("World.heartbeat_timeout", mw.heartbeat_timeout)]
    delays += [(f"start latency of {p!r}", lat) for p, lat in mw.latency]
    delays += [(f"lease start-up of {p!r}", t) for p, t in mw.lease] + [("Lease idle_s", mw.lease_idle_s)]
    out += [(1.0 / d, f"{what} {d:g} s") for what, d in delays if d > 0]
    out += [(mw.phases / w, f"warm-up of {g!r} {w:g} s") for g, w in mw.warmup]
    out += [(r, f"random requirement change {c.label or c} every {1.0 / r:g} s") for c, r in mw.changes]
    out += [(r, f"load steps of {p!r} every {1.0 / r:g} s") for p, _r, _lv, r in mw.loads]
    out += [(r, f"{e} (a {k} variable) at {r:g} per s") for k, _s, rates in mw.timed for e, r in rates]
    out.append((1.0 / horizon, f"the horizon {horizon:g} s (--horizon)"))
    return out


def check_rates(mw: MarkovWorld, horizon: float) -> None:
    """Refuse, in one line naming the two, rates the solvers cannot take in double
    precision: one that is not a finite positive number (a mean of a subnormal number
    of seconds), or a fastest rate more than :data:`RATE_RATIO` times the slowest."""
    rates = named_rates(mw, horizon)
    for r, what in rates:
        if not is_rate(r):
            raise AnalysisError(f"{what} gives a rate of {r:g} per second, which double precision cannot hold: give a mean of at least 1e-300 s")
    fast = max(rates, key=lambda x: x[0])
    slow = min(rates, key=lambda x: x[0])
    if fast[0] > RATE_RATIO * slow[0]:
        raise AnalysisError(
            f"{fast[1]} against {slow[1]}: the fastest rate is {fast[0] / slow[0]:.1e} times the slowest, more than the "
            f"{RATE_RATIO:.0e} the solvers take in double precision (the slow rate is lost beside the fast one, and a mission "
            f"needs about that many steps); bring the two within a factor {RATE_RATIO:.0e} of each other"
        )
