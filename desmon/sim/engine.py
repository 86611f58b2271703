"""The SimPy world: robot, sensors, platforms, fault injector, context monitor,
infrastructure (the Control port) and the deployer's process, with the audit.

Every process is a thin shell around the pure deployment core
(:class:`desmon.deployment.core.DeploymentCore`): it waits, reads the clock and calls
the core; no decision is made here.

* **Robot** walks the task's ground-truth segments; each new action becomes a gripper /
  base observation that the context monitor interprets (``deployment.monitor.interpret``)
  after the recognition delay. An action the gripper does not show (``rotate_*``, a
  model's own actions) is recognised directly, after the same delay. A model's own
  action has the sensor signals of the built-in it is declared ``like``.
* **Context monitor** inserts facts into the networkx repository through the core's
  Insert port (context, HAS_DEVICE loss / repair noticed after the heartbeat timeout,
  platform up / down, background load). The repository's Notify subscription wakes the
  deployer process.
* **Deployer process** drives ``core.reaction(stimulus)``: each ``Start`` waits the
  platform's start latency and then succeeds or fails by the world's failure model only
  (platform down, scripted or seeded random failure). The infrastructure does *not*
  check Capacity -- that is the core's decision: a start the deployer asks for on a
  platform without room really over-commits it, and the audit (``no-overcommit``)
  reports it. A success starts the detector process (consuming its spec's
  ``consumption()``) and ``record_start``\\ s the DEPLOYED_ON edge; ``Stop`` frees the memory and records the
  DEPLOYMENT_HISTORY; ``RaiseError`` is stamped with ``env.now``. After every reaction
  ``core.settle`` and, when no newer fact is pending, the named invariants are audited
  on the live repository.
* **Detector processes** consume every sample of their devices since the last wake-up,
  in one vectorised call. They wake on the ``world.block`` grid around ground-truth
  slips (``SLIP_WINDOW``) and every ``world.quiet_block`` seconds (on the same grid)
  elsewhere; the detectors are chunking-invariant and nothing in the world reads their
  output back, so this changes only where an alarm record lands in the trace.
* **Fault injector** fails and repairs devices and platforms (script or MTTF / MTTR);
  **load** processes change the background memory load (script or random walk).
"""

from __future__ import annotations

import bisect
import math
import random
from dataclasses import dataclass, field
from typing import Any, Callable

import simpy

from desmon.deployment.guard import DeployerFault
from desmon.deployment.control import ControlRules
from desmon.deployment.core import DeploymentCore, not_a_command, stamp
from desmon.deployment.invariants import check_invariants
from desmon.deployment.monitor import GripperObservation, Stimulus, interpret
from desmon.deployment.ports import ErrorRecord, RaiseError, Start, Stop
from desmon.deployment.validity import ScalarChecks
from desmon.detectors.base import Alarm
from desmon.model.actions import GRASP, HOLD, IDLE, MOVE_BASE, RELEASE
from desmon.deployment.lease import lease_choice
from desmon.deployment.ports import NO_ACCEPTABLE_PLATFORMS
from desmon.model.events import (
    ActionChange,
    DeviceEvent,
    DeviceFail,
    DeviceRepair,
    Event,
    LoadChange,
    PlatformDown,
    PlatformEvent,
    PlatformJoin,
    PlatformLeave,
    PlatformUp,
    RequirementChange,
)
from desmon.model.scenario import Scenario
from desmon.model.system import PlatformState
from desmon.repository import labels as L
from desmon.repository.facts import RepositoryInsert, load_model, record_start, record_stop
from desmon.repository.query import RepositoryQuery
from desmon.repository.store import ADD_EDGE, REMOVE_EDGE, RELABEL_EDGE, UPDATE_NODE, Repository
from desmon.sim.metrics import Exposure, MemoryMeter, slip_metrics
from desmon.sim.sensors import DetectorAdapter, SensorBank
from desmon.sim.trace import Trace, declared_actions, graph_resources, initial_loads, platform_resources
from desmon.detectors.signals import Segment
from desmon.sim.world import Slip, World, draw_slips, expand_task, like_segments, world_of

__all__ = ["SimWorld", "RunResult", "simulate", "OBSERVATION", "SLIP_WINDOW"]

#: Around a ground-truth slip at t_s, detectors wake every ``world.block`` seconds in
#: [t_s + lo, t_s + hi] (a pulled slip loads the wrist up to 1 s before motion onset;
#: the detection window ends 1 s after it).
SLIP_WINDOW = (-2.0, 2.0)

#: What the context monitor sees of gripper and base in each ground-truth action; an
#: action not listed here (rotate_*, a model's own actions) is recognised directly.
OBSERVATION = {
    GRASP: GripperObservation("closing"),
    RELEASE: GripperObservation("opening"),
    MOVE_BASE: GripperObservation("closed", base_moving=True),
    HOLD: GripperObservation("closed"),
    IDLE: GripperObservation("open", holding=False),
}


@dataclass
class Instance:
    """A running detector: a graph started on a platform by the infrastructure."""

    graph: str
    platform: str
    memory: float
    streams: dict[str, tuple[str, ...]]  # stream -> devices read
    adapter: DetectorAdapter | None
    started: float
    valid_from: float = math.inf
    fed: float = 0.0
    halted: bool = False
    proc: Any = None
    gen: int = 0  # activations so far (a warm-up end of an older one is ignored)


@dataclass
class RunResult:
    """Everything a run produced."""

    scenario: Scenario
    world: World
    deployer: str
    seed: int
    horizon: float
    trace: Trace
    repo: Repository
    metrics: dict[str, Any]
    decisions: list[dict[str, Any]]
    errors: list[ErrorRecord]
    violations: list[tuple[float, str, str]]
    slips: tuple[Slip, ...]
    alarms: list[Alarm]
    events: int = 0


class SimWorld:
    """One simulation of a scenario (see the module docstring)."""

    def __init__(
        self,
        scenario: Scenario,
        *,
        deployer: str = "desmon",
        seed: int = 0,
        until: float | None = None,
        trace: Trace | None = None,
        signals: bool | None = None,
        progress: Callable[[float, float], None] | None = None,
        on_quiescent: "Callable[[SimWorld], None] | None" = None,
    ) -> None:
        self.scenario = scenario
        #: called with this world at every quiescent point, after its audit (a conformance
        #: harness compares the world there with the checker's state; None: nobody asks)
        self.on_quiescent = on_quiescent
        self.model = scenario.model
        self.world = world_of(scenario)
        self.seed = int(seed)
        self.horizon = float(until if until is not None else self.world.horizon)
        self.signals_on = self.world.signals if signals is None else bool(signals)
        self.trace = trace if trace is not None else Trace()
        self.progress = progress
        self.env = simpy.Environment()
        env = self.env
        self.repo = Repository(clock=lambda: env.now)
        load_model(self.repo, self.model)
        self.query = RepositoryQuery(self.repo, ScalarChecks())  # its own memoised checks
        self.core = DeploymentCore(self.model, self.query, RepositoryInsert(self.repo, self.model.robot), deployer)
        self.deployer_name = self.core.deployer.name
        self._init_physical()
        self._init_ground_truth()
        self._init_metrics()
        self._apply_initial(scenario)
        self._init_pending()
        # Notify: repository changes wake the deployer
        self.repo.subscribe(self._notify, ops=(ADD_EDGE, REMOVE_EDGE, UPDATE_NODE), labels=(L.IN_CONTEXT, L.HAS_DEVICE, L.PLATFORM))
        self.repo.subscribe(self._count_history, ops=(RELABEL_EDGE,), labels=(L.DEPLOYMENT_HISTORY,))

    def _init_pending(self) -> None:
        """What the deployer process has yet to react to, and the event that wakes it."""
        self.pending_platforms: dict[str, None] = {}
        self.pending_context = False
        self.pending_specs: dict[str, None] = {}
        self.wake: simpy.Event | None = None

    def _init_physical(self) -> None:
        """Platforms up (an on-demand one absent until it joins), loads, devices, instances."""
        self.up = {p.name: not p.on_demand for p in self.model.platforms}
        self.load: dict[str, float] = {p.name: 0.0 for p in self.model.platforms}
        self.dev_ok = {d.name: True for d in self.model.devices}
        self.host = {d.name: d.platform for d in self.model.devices}
        self._hosted = {p.name: self.model.devices_on(p.name) for p in self.model.platforms}
        #: the one Control semantics (desmon.deployment.control), on the physical facts
        self.rules = ControlRules(self.model, self.query.deployment_information, self.query.checks)
        self.instances: dict[tuple[str, str], Instance] = {}
        #: memory (MB) a running instance of each graph consumes: its spec's consumption()
        self.consumes = {s.graph: dict(s.consumption()).get("memory", 0.0) for s in self.model.specs}
        self.stops = 0
        self.history_edges = 0
        self.attempts: dict[tuple[str, str], int] = {}
        self.rng_start = random.Random(f"{self.seed}:start")

    def _init_ground_truth(self) -> None:
        """Task segments, slips and (with signals on) the sensor bank."""
        self.segments: tuple[Segment, ...] = expand_task(self.world, self.horizon)
        #: the same segments as the signals see them: each action replaced by the built-in it is like
        physical = like_segments(self.segments, self.model.like)
        self.slips = draw_slips(self.world, physical, self.seed)
        self.slips = tuple(s for s in self.slips if s.time < self.horizon)
        self._busy = _merge_windows([(s.time + SLIP_WINDOW[0], s.time + SLIP_WINDOW[1]) for s in self.slips])
        devs = [(d, self.world.signal_of(d.kind)) for d in self.model.devices]
        self.stream_of = {d.name: s for d, s in devs}
        self.bank: SensorBank | None = None
        if self.signals_on:
            self.bank = SensorBank(physical, self.slips, self.seed, [(d, s) for d, s in devs if s is not None])

    def _init_metrics(self) -> None:
        self.exposure = Exposure(self._valid_from, self._emit_exposure)
        self.memory = MemoryMeter({p.name: p.capacity("memory") or math.inf for p in self.model.platforms})
        self.alarms: list[Alarm] = []
        self.decisions: list[dict[str, Any]] = []
        self.errors: list[ErrorRecord] = []
        self.violations: list[tuple[float, str, str]] = []
        self.starts = self.start_failures = self.migrations = self.reactions = self.audits = 0
        #: upgrades back to a preferred alternative (break-before-make), failed ones, and
        #: the seconds their slots went unserved (stop of the fallback -> ready)
        self.upgrades = self.upgrades_failed = 0
        self.upgrade_blind = 0.0
        #: run-time changes: requirement changes applied, leases (requested, joined), leased seconds
        self.requirement_changes = self.leases = 0
        self.leased_s = 0.0
        self._leased: dict[str, float] = {}  # on-demand platform -> join time, while leased
        self._lease_requested: set[str] = set()
        self._last_busy: dict[str, float] = {}
        self._pending_ready: list[Instance] = []

    def _apply_initial(self, scenario: Scenario) -> None:
        """The scenario's initial facts, silently (before Notify is wired)."""
        for ev in scenario.initial:
            if isinstance(ev, PlatformEvent):
                self._platform_flip(ev.platform, ev.up, 0.0)
            else:
                self._apply_physical(ev, 0.0)
            self.core.observe(ev)
            if isinstance(ev, RequirementChange):
                self._follow_consumption(ev.graph)
        for p in self.up:
            self.memory.set(p, 0.0, self._used(p))

    # ------------------------------------------------------------------ physical state
    def _apply_physical(self, ev: Event, t: float) -> None:
        if isinstance(ev, LoadChange) and ev.resource == "memory":
            self.load[ev.platform] = ev.amount
        elif isinstance(ev, DeviceEvent):
            self.dev_ok[ev.device] = ev.working
            if self.bank is not None and self.up[self.host[ev.device]]:  # else silent (until it is up)
                (self.bank.repair if ev.working else self.bank.fail)(ev.device, t)

    def _used(self, p: str) -> float:
        if not self.up[p]:
            return 0.0
        return self.load[p] + sum(i.memory for i in self.instances.values() if i.platform == p)

    def _mem(self, p: str) -> None:
        self.memory.set(p, self.env.now, self._used(p))

    def _readable(self, device: str) -> bool:
        """A device's signal reaches a detector while it works and its platform is up."""
        return self.dev_ok[device] and self.up[self.host[device]]

    def _inputs_ok(self, inst: Instance) -> bool:
        return all(any(self._readable(d) for d in devs) for devs in inst.streams.values())

    def _physical_state(self, platform: str) -> PlatformState:
        """The physical facts of ``platform`` the Control rules read (up, working devices)."""
        return PlatformState(
            self.model.platform(platform),
            self.up[platform],
            tuple(d for d in self._hosted[platform] if self.dev_ok[d.name]),
        )

    def _alive(self, inst: Instance) -> bool:
        return self.up[inst.platform] and not inst.halted and self._inputs_ok(inst)

    def _valid_from(self, graph: str) -> float:
        best = math.inf
        for inst in self.instances.values():
            if inst.graph == graph and self._alive(inst):
                best = min(best, inst.valid_from)
        return best

    # ------------------------------------------------------------------ Notify
    def _notify(self, change: Any) -> None:
        if change.label == L.IN_CONTEXT:
            self.pending_context = True
        elif change.label == L.HAS_DEVICE:
            self.pending_platforms[self.repo.graph.nodes[change.source]["name"]] = None
        elif change.label == L.PLATFORM and change.op == UPDATE_NODE:
            self.pending_platforms[self.repo.graph.nodes[change.node]["name"]] = None
        if self.wake is not None and not self.wake.triggered:
            self.wake.succeed()

    def _emit_exposure(self, t: float, state: str, context: str) -> None:
        self.trace.emit(t, "exposure", state=state, context=context)

    def _count_history(self, change: Any) -> None:
        self.history_edges += 1

    def _take_stimulus(self) -> Stimulus:
        stim = Stimulus(tuple(self.pending_platforms), self.pending_context, tuple(self.pending_specs))
        self.pending_platforms = {}
        self.pending_context = False
        self.pending_specs = {}
        return stim

    def _pending(self) -> bool:
        return bool(self.pending_platforms or self.pending_context or self.pending_specs)

    # ------------------------------------------------------------------ processes
    def _robot(self):  # type: ignore[no-untyped-def]
        env = self.env
        risky = self.model.risky_actions
        for seg in self.segments:
            if seg.start > env.now:
                yield env.timeout(seg.start - env.now)
            # the selector's slots in the TRUE context, kept apart (one covered slot does
            # not hide an uncovered one); the core's selector gives them for the recognised
            # one. Exposure counts risky contexts only (an object in the hand).
            slots = self.model.rules.slots_for(seg.context) if seg.context in risky else ()
            self.trace.emit(env.now, "action", action=seg.context, duration=seg.duration)
            self.exposure.set_wanted(env.now, slots, seg.context)
            env.process(self._recognise(seg.context))

    def _recognise(self, action: str):  # type: ignore[no-untyped-def]
        if self.world.recognition_delay:
            yield self.env.timeout(self.world.recognition_delay)
        obs = OBSERVATION.get(action)
        context = interpret(obs) if obs is not None else action
        self._insert(ActionChange(context))

    def _insert(self, ev: Event) -> None:
        """The context monitor writes a fact (Insert); Notify does the rest."""
        stim = self.core.observe(ev)
        if not stim.empty:
            self.trace.emit(self.env.now, "fact", fact=str(ev))

    def _notice(self, ev: Event):  # type: ignore[no-untyped-def]
        if self.world.heartbeat_timeout:
            yield self.env.timeout(self.world.heartbeat_timeout)
        self._insert(ev)

    def _fault(self, ev: Event, source: str) -> None:
        """The fault injector changes the physical world; the monitor notices later."""
        env = self.env
        now = env.now
        if isinstance(ev, DeviceEvent):
            if self.dev_ok[ev.device] == ev.working:
                return
            self.trace.emit(now, "fault", event=str(ev), source=source)
            self.exposure.advance(now)
            readers = [i for i in self.instances.values() if any(ev.device in devs for devs in i.streams.values())]
            self._inputs_change(readers, now, lambda: self._apply_physical(ev, now))
        else:
            up = ev.up
            if self.up[ev.platform] == up:
                return
            self.trace.emit(now, "fault", event=str(ev), source=source)
            self.exposure.advance(now)
            hosted = {d.name for d in self._hosted[ev.platform]}
            readers = [
                i for i in self.instances.values()
                if i.platform != ev.platform and any(d in hosted for devs in i.streams.values() for d in devs)
            ]
            self._inputs_change(readers, now, lambda: self._platform_flip(ev.platform, up, now))
            self.trace.emit(now, "platform", platform=ev.platform, up=up)
        self._flush_ready()
        self.exposure.check(now)
        env.process(self._notice(ev))

    def _inputs_change(self, readers: list[Instance], now: float, change: Callable[[], None]) -> None:
        """Apply ``change`` to the physical world; instances on other platforms reading the
        affected devices (``readers``) are fed up to ``now`` first, re-activated when their
        inputs come back, and reported invalid when they lose them."""
        before = {id(i): self._alive(i) for i in readers}
        ok_before = {id(i): self._inputs_ok(i) for i in readers}
        for inst in readers:
            self._feed(inst, now)
        change()
        for inst in readers:
            if not ok_before[id(inst)] and self._inputs_ok(inst) and self.up[inst.platform]:
                self._activate(inst, now)  # input back: re-tare / warm up
            elif before[id(inst)] and not self._alive(inst):
                self.trace.emit(now, "invalid", graph=inst.graph, platform=inst.platform, reason="sensor_failure")

    def _platform_flip(self, platform: str, up: bool, now: float) -> None:
        """A platform goes down (its instances halt, its devices go silent) or comes back
        (the supervisor restarts its instances, its working devices stream again)."""
        for inst in [i for i in self.instances.values() if i.platform == platform]:
            if up:
                inst.fed = now
                inst.halted = False
                self._activate(inst, now)  # the supervisor restarts it on reboot
            else:
                alive = self._alive(inst)
                self._feed(inst, now)
                inst.halted = True
                inst.valid_from = math.inf
                if inst.adapter is not None:
                    inst.adapter.deactivate()
                if alive:
                    self.trace.emit(now, "invalid", graph=inst.graph, platform=inst.platform, reason="platform_crash")
        self.up[platform] = up
        if self.bank is not None:
            for d in self._hosted[platform]:
                if self.dev_ok[d.name]:
                    (self.bank.repair if up else self.bank.fail)(d.name, now)
        self._mem(platform)

    def _scripted_faults(self):  # type: ignore[no-untyped-def]
        for te in self.world.faults:
            if te.time >= self.horizon:
                break
            if te.time > self.env.now:
                yield self.env.timeout(te.time - self.env.now)
            self._fault(te.event, te.label or "script")

    def _stochastic(self, component: str, mttf: float, mttr: float):  # type: ignore[no-untyped-def]
        rng = random.Random(f"{self.seed}:fault:{component}")
        is_dev = component in self.dev_ok
        while True:
            yield self.env.timeout(rng.expovariate(1.0 / mttf))
            self._fault(DeviceFail(component) if is_dev else PlatformDown(component), "mttf")
            yield self.env.timeout(rng.expovariate(1.0 / mttr))
            self._fault(DeviceRepair(component) if is_dev else PlatformUp(component), "mttr")

    def _set_load(self, ev: LoadChange) -> None:
        if ev.resource == "memory":
            self.load[ev.platform] = ev.amount
            self._mem(ev.platform)
        self.trace.emit(self.env.now, "load", platform=ev.platform, resource=ev.resource, amount=ev.amount)
        self._insert(ev)

    def _scripted_loads(self):  # type: ignore[no-untyped-def]
        for te in self.world.loads:
            if te.time >= self.horizon:
                break
            if te.time > self.env.now:
                yield self.env.timeout(te.time - self.env.now)
            self._set_load(te.event)  # type: ignore[arg-type]

    def _walk(self, i: int):  # type: ignore[no-untyped-def]
        w = self.world.load_walks[i]
        rng = random.Random(f"{self.seed}:load:{w.platform}:{i}")
        x = w.start
        self._set_load(LoadChange(w.platform, round(x, 1), w.resource))
        while True:
            yield self.env.timeout(w.interval)
            x = min(w.high, max(w.low, x + w.drift + rng.gauss(0.0, w.sigma)))
            self._set_load(LoadChange(w.platform, round(x, 1), w.resource))

    # ------------------------------------------------------------------ run-time changes
    def _change(self, ev: Event, source: str) -> None:
        """A scripted or random run-time change: a requirement change is written by the
        context monitor at once (it is a decision of the robot's software, not a fault to
        be noticed); a platform joins or leaves like a platform that comes up or goes down."""
        if isinstance(ev, PlatformEvent):
            self._fault(ev, source)
            if ev.up:
                self._leased.setdefault(ev.platform, self.env.now)
            elif ev.platform in self._leased:
                self.leased_s += self.env.now - self._leased.pop(ev.platform)
            return
        now = self.env.now
        self.trace.emit(now, "change", event=str(ev), source=source)
        stim = self.core.observe(ev)
        if stim.empty:
            return
        self.requirement_changes += 1
        self._follow_consumption(ev.graph)
        self.trace.emit(now, "consumption", graph=ev.graph, resources=graph_resources(self.query.deployment_information(ev.graph)))
        self.trace.emit(now, "fact", fact=str(ev))
        self.pending_platforms.update(dict.fromkeys(stim.changed_platforms))
        self.pending_specs.update(dict.fromkeys(stim.specs_changed))
        if self.wake is not None and not self.wake.triggered:
            self.wake.succeed()

    def _follow_consumption(self, graph: str) -> None:
        """What ``graph`` consumes follows its current specification, running instances included."""
        spec = self.query.deployment_information(graph)
        memory = dict(spec.consumption()).get("memory", 0.0) if spec is not None else 0.0
        self.consumes[graph] = memory
        for inst in self.instances.values():
            if inst.graph == graph:  # a running instance now needs what its spec says
                inst.memory = memory
                self._mem(inst.platform)

    def _scripted_changes(self):  # type: ignore[no-untyped-def]
        for te in self.world.changes:
            if te.time >= self.horizon:
                break
            if te.time > self.env.now:
                yield self.env.timeout(te.time - self.env.now)
            self._change(te.event, te.label or "script")

    def _random_changes(self):  # type: ignore[no-untyped-def]
        spec = self.world.random_changes
        assert spec is not None
        rng = random.Random(f"{self.seed}:changes")
        while True:
            yield self.env.timeout(rng.expovariate(1.0 / spec.mean_interval))
            self._change(rng.choice(spec.changes), "random")

    def _maybe_lease(self, graph: str) -> None:
        """No acceptable platform for ``graph``: lease an on-demand platform on which it
        would be acceptable (:func:`desmon.deployment.lease.lease_choice`), unless one is
        already on its way."""
        lease = self.world.lease
        assert lease is not None
        allowed = lease.platforms or tuple(p.name for p in self.model.platforms if p.on_demand)
        absent = [p for p in allowed if not self.up[p] and p not in self._lease_requested]
        choice = lease_choice(self.query, graph, absent) if absent else None
        if choice is None:
            return
        self._lease_requested.add(choice)
        self.leases += 1
        self.trace.emit(self.env.now, "lease", platform=choice, graph=graph)
        self.env.process(self._lease(choice))

    def _lease(self, platform: str):  # type: ignore[no-untyped-def]
        """A leased platform joins after its start-up delay and leaves once it has hosted
        nothing for the lease's ``idle_s``."""
        env = self.env
        idle = self.world.lease.idle_s  # type: ignore[union-attr]
        yield env.timeout(self.model.platform(platform).startup_s)
        self._change(PlatformJoin(platform), "lease")
        self._last_busy[platform] = env.now
        while True:
            busy = any(p == platform for _g, p in self.instances)
            wait = idle if busy else idle - (env.now - self._last_busy[platform])
            if not busy and wait <= 0:
                break
            yield env.timeout(max(wait, 1e-6))
        self._change(PlatformLeave(platform), "lease")
        self._lease_requested.discard(platform)

    def _progress(self):  # type: ignore[no-untyped-def]
        step = self.horizon / 20
        while True:
            yield self.env.timeout(step)
            if self.progress is not None:
                self.progress(self.env.now, self.horizon)

    # ------------------------------------------------------------------ infrastructure (Control)
    def _devices_for(self, graph: str, platform: str) -> dict[str, tuple[str, ...]]:
        out: dict[str, tuple[str, ...]] = {}
        for kind, devices in self.rules.input_devices(graph, platform):
            devs = tuple(d.name for d in devices)
            stream = self.world.signal_of(kind) or kind
            out[stream] = out.get(stream, ()) + devs
        return out

    def _activate(self, inst: Instance, now: float) -> None:
        inst.fed = now
        if inst.adapter is not None and inst.adapter.det is None:
            # signals on, but what the graph reads has no signal model (World.no_signal_model):
            # it runs and uses memory, yet can never alarm, so it never becomes valid and
            # never counts as monitoring (the run report lists it)
            inst.valid_from = math.inf
            inst.gen += 1
            if self.instances.get((inst.graph, inst.platform)) is inst:  # its input is back: say so (no ready follows)
                self.trace.emit(now, "no_signal", graph=inst.graph, platform=inst.platform)
            return
        warm = inst.adapter.warmup if inst.adapter is not None else 0.0
        inst.valid_from = now + warm
        inst.gen += 1
        if inst.adapter is not None:
            inst.adapter.activate(now)
        if warm > 0:
            gen = inst.gen
            self.env.timeout(warm).callbacks.append(lambda _ev: self._warmed(inst, gen))
        else:
            self._pending_ready.append(inst)  # valid at once: reported once it is registered

    def _warmed(self, inst: Instance, gen: int) -> None:
        """A warm-up ended: report the instance ready if it is still that activation and alive."""
        now = self.env.now
        if inst.gen == gen and self.instances.get((inst.graph, inst.platform)) is inst and self._alive(inst):
            self.trace.emit(now, "ready", graph=inst.graph, platform=inst.platform)
        self.exposure.check(now)

    def _flush_ready(self) -> None:
        while self._pending_ready:
            inst = self._pending_ready.pop(0)
            self._warmed(inst, inst.gen)

    def _start(self, graph: str, platform: str):  # type: ignore[no-untyped-def]
        """Control.start: latency, then success or failure; returns the outcome."""
        env = self.env
        if (graph, platform) in self.instances:
            return True
        n = self.attempts[(graph, platform)] = self.attempts.get((graph, platform), 0) + 1
        latency = self.world.latency(platform)
        if latency:
            yield env.timeout(latency)
        reason = self.rules.start_refusal(graph, platform, self._physical_state) or ""
        if reason:
            pass
        elif (graph, platform, n) in self.world.start_failure.script:
            reason = "scripted start failure"
        elif self.world.start_failure.probability and self.rng_start.random() < self.world.start_failure.probability:
            reason = "start failed"
        if reason:
            self.start_failures += 1
            return reason
        if (graph, platform) in self.instances:
            return True
        self.exposure.advance(env.now)
        streams = self._devices_for(graph, platform)
        adapter = DetectorAdapter(frozenset(streams), graph) if self.signals_on else None
        inst = Instance(graph, platform, self.consumes.get(graph, 0.0), streams, adapter, env.now)
        self._activate(inst, env.now)
        self.instances[(graph, platform)] = inst
        self._last_busy[platform] = env.now
        self.starts += 1
        record_start(self.repo, graph, platform)
        self._mem(platform)
        self._flush_ready()
        self.exposure.check(env.now)
        if adapter is not None and adapter.det is not None:
            inst.proc = env.process(self._detector(inst))
        return True

    def _stop(self, graph: str, platform: str) -> bool:
        """Control.stop: free the memory, end the process, record DEPLOYMENT_HISTORY."""
        inst = self.instances.get((graph, platform))
        if inst is None:
            return False
        now = self.env.now
        self.exposure.advance(now)
        self._feed(inst, now)
        del self.instances[(graph, platform)]
        self._last_busy[platform] = now
        if inst.proc is not None and inst.proc.is_alive:
            inst.proc.interrupt("stop")
        if inst.adapter is not None:
            inst.adapter.deactivate()
        self.stops += 1
        record_stop(self.repo, graph, platform)
        self._mem(platform)
        self.exposure.check(now)
        return True

    def _next_wake(self, now: float) -> float:
        """The next detector wake-up after ``now``: the next ``block`` grid point while a
        slip window is near, else the grid point ``quiet_block`` ahead (or the grid point
        that starts the next slip window, whichever comes first)."""
        block = self.world.block
        k = math.floor(now / block + 1e-9) + 1
        nxt = k * block
        quiet = self.world.quiet_block
        if quiet <= block:
            return nxt
        far = max(nxt, math.floor((now + quiet) / block + 1e-9) * block)
        lo, hi = self._busy
        i = bisect.bisect_right(hi, now)
        if i < len(lo) and lo[i] < far:
            if lo[i] <= nxt:
                return nxt
            return max(nxt, math.floor(lo[i] / block + 1e-9) * block)
        return far

    def _detector(self, inst: Instance):  # type: ignore[no-untyped-def]
        env = self.env
        try:
            while True:
                yield env.timeout(self._next_wake(env.now) - env.now)
                self._feed(inst, env.now)
        except simpy.Interrupt:
            return

    def _feed(self, inst: Instance, t1: float) -> None:
        t0 = inst.fed
        if t1 <= t0:
            return
        inst.fed = t1
        if inst.halted or inst.adapter is None or self.bank is None or not self.up[inst.platform]:
            return
        alarms = inst.adapter.feed(self.bank, t0, t1, inst.streams)
        for a in alarms:
            self.alarms.append(a)
            self.trace.emit(a.time, "alarm", detector=inst.graph, platform=inst.platform, direction=a.direction)

    # ------------------------------------------------------------------ the deployer's process
    def _deployer(self):  # type: ignore[no-untyped-def]
        env = self.env
        while True:
            if not self._pending():
                self.wake = env.event()
                yield self.wake
                self.wake = None
            stim = self._take_stimulus()
            self.reactions += 1
            ctx = self.query.context()
            self.trace.emit(env.now, "reaction", context=ctx, changed=list(stim.changed_platforms), context_changed=stim.context_changed)
            book = _Reaction(self.core.slots())  # what this reaction serves, even if the context moves on meanwhile
            reaction = self.core.reaction(stim)
            outcome: bool | None = None
            while True:
                try:
                    cmd = reaction.send(outcome)
                except StopIteration:
                    break
                except DeployerFault as fault:  # where in the run: the first reaction means it cannot run at all
                    fault.initial = self.reactions == 1
                    fault.args = (f"at t={env.now:g} s, {fault.args[0]}",)
                    raise
                if isinstance(cmd, Start):
                    outcome = yield from self._command_start(cmd, book)
                elif isinstance(cmd, Stop):
                    outcome = self._command_stop(cmd, book)
                elif isinstance(cmd, RaiseError):
                    outcome = None
                    self._command_error(cmd, book)
                else:
                    raise not_a_command(cmd)
            self.core.settle(book.raised)
            quiescent = not self._pending()
            for name, msg in self.core.findings:  # transition properties (no-flapping, errors-justified, ...)
                # the others judge the reaction on the facts it left: only at a quiescent point
                if name == "no-flapping" or quiescent:
                    self.violations.append((env.now, name, msg))
                    self.trace.emit(env.now, "violation", invariant=name, message=msg)
            if quiescent:
                self._audit()

    def _command_start(self, cmd: Start, book: "_Reaction"):  # type: ignore[no-untyped-def]
        """Execute a Start of the reaction (latency, outcome) and count what it means."""
        issued = self.env.now
        res = yield from self._start(cmd.graph, cmd.platform)
        outcome = res is True
        elsewhere = [p for (g, p) in self.instances if g == cmd.graph and p != cmd.platform]
        if outcome and (elsewhere or book.stopped_here.get(cmd.graph, cmd.platform) != cmd.platform):
            self.migrations += 1
        if outcome and book.stopped_at:
            self._count_upgrade(cmd.graph, cmd.platform, book.slots, book.stopped_at, book.tried)
        elif not outcome:
            book.tried.add(cmd.graph)
        self._decision("start", cmd.graph, cmd.platform, outcome, issued, "" if outcome else str(res))
        return outcome

    def _command_stop(self, cmd: Stop, book: "_Reaction") -> bool:
        issued = self.env.now
        outcome = self._stop(cmd.graph, cmd.platform)
        if outcome:
            book.stopped_here[cmd.graph] = cmd.platform
            if any(cmd.graph in slot and len(slot) > 1 for slot in book.slots):
                book.stopped_at[cmd.graph] = self.env.now
        self._decision("stop", cmd.graph, cmd.platform, outcome, issued, "")
        return outcome

    def _command_error(self, cmd: RaiseError, book: "_Reaction") -> None:
        rec = stamp(cmd, self.env.now)
        self.errors.append(rec)
        book.raised.append(cmd.graph)
        self.trace.emit(self.env.now, "error", kind=rec.kind, graph=rec.graph, platform=rec.platform, detail=rec.detail)
        if cmd.kind == NO_ACCEPTABLE_PLATFORMS and self.world.lease is not None:
            self._maybe_lease(cmd.graph)

    def _count_upgrade(
        self, graph: str, platform: str, slots: tuple[tuple[str, ...], ...], stopped_at: dict[str, float], tried: set[str]
    ) -> None:
        """``graph`` started in a reaction that stopped a wanted alternative of its slot:
        an upgrade if ``graph`` is preferred to the stopped one; a failed upgrade if a
        preferred alternative's start failed in between and a fallback is placed again.
        Either way the slot went unserved from that stop until the started detector is
        ready: the upgrade's blind time. (A fallback that simply migrates is neither.)"""
        for slot in slots:
            if graph not in slot:
                continue
            mine = slot.index(graph)
            gone = [(slot.index(f), t) for f, t in stopped_at.items() if f in slot]
            if not gone:
                continue
            if any(i > mine for i, _t in gone):
                self.upgrades += 1
            elif any(slot.index(h) < min(i for i, _t in gone) for h in tried if h in slot):
                self.upgrades_failed += 1
            else:
                return
            ready = self.instances[(graph, platform)].valid_from
            if math.isfinite(ready):
                self.upgrade_blind += ready - min(t for _i, t in gone)
            for f in [f for f in stopped_at if f in slot]:
                del stopped_at[f]
            return

    def _decision(self, what: str, graph: str, platform: str, ok: bool, issued: float, why: str) -> None:
        rec = {"t": round(self.env.now, 6), "issued": round(issued, 6), "command": what, "graph": graph, "platform": platform, "ok": ok}
        if why:
            rec["why"] = why
        self.decisions.append(rec)
        self.trace.emit(self.env.now, "decision", command=what, graph=graph, platform=platform, ok=ok, issued=issued, why=why)

    def _audit(self) -> None:
        self.audits += 1
        running = tuple(sorted(self.instances))
        view = self.core.view(running=running, stops=self.stops, history=self.history_edges)
        for name, msg in check_invariants(view):
            self.violations.append((self.env.now, name, msg))
            self.trace.emit(self.env.now, "violation", invariant=name, message=msg)
        if self.on_quiescent is not None:
            self.on_quiescent(self)

    def physically_valid(self, graph: str, platform: str) -> bool:
        """Whether the running instance of ``graph`` on ``platform`` can monitor: its
        platform is up and every stream it reads has a readable device (warm-up aside)."""
        inst = self.instances.get((graph, platform))
        return inst is not None and self.up[platform] and self._inputs_ok(inst)

    # ------------------------------------------------------------------ run
    def _start_processes(self) -> None:
        """Register the robot, the deployer and the world's fault, load and change processes."""
        env = self.env
        env.process(self._robot())
        env.process(self._deployer())
        if self.world.faults:
            env.process(self._scripted_faults())
        for m in self.world.stochastic_faults:
            env.process(self._stochastic(m.component, m.mttf, m.mttr))
        if self.world.loads:
            env.process(self._scripted_loads())
        for i in range(len(self.world.load_walks)):
            env.process(self._walk(i))
        if self.world.changes:
            env.process(self._scripted_changes())
        if self.world.random_changes is not None:
            env.process(self._random_changes())

    def run(self) -> RunResult:
        env = self.env
        self.trace.emit(
            0.0, "run", scenario=self.scenario.name, deployer=self.deployer_name, seed=self.seed, horizon=self.horizon,
            signals=self.signals_on,
            platforms={p.name: platform_resources(p) for p in self.model.platforms},
            graphs={
                g.name: {**graph_resources(self.query.deployment_information(g.name)), "memory": self.consumes.get(g.name, 0.0)}
                for g in self.model.graphs
            },
            actions=declared_actions(self.model),
        )
        for p in self.model.platforms:
            self.trace.emit(0.0, "load", platform=p.name, resource="memory", amount=self.load[p.name])
        for p, resource, amount in initial_loads(self.model, self.scenario.initial):
            self.trace.emit(0.0, "load", platform=p, resource=resource, amount=amount)
        for s in self.slips:
            self.trace.emit(s.time, "slip", direction=s.direction, kind=s.kind)
        self._start_processes()
        if self.progress is not None:
            env.process(self._progress())
        env.run(until=self.horizon)
        now = self.horizon
        for inst in list(self.instances.values()):
            self._feed(inst, now)
        self.exposure.close(now)
        self.memory.close(now)
        for platform, since in self._leased.items():
            self.leased_s += now - since
        metrics = self._metrics()
        self.trace.emit(now, "end", **{k: v for k, v in metrics.items() if k != "latencies"})
        return RunResult(
            self.scenario, self.world, self.deployer_name, self.seed, self.horizon, self.trace, self.repo, metrics,
            self.decisions, self.errors, self.violations, self.slips, self.alarms,
        )

    def _metrics(self) -> dict[str, Any]:
        ex = self.exposure
        by_kind: dict[str, int] = {}
        for e in self.errors:
            by_kind[e.kind] = by_kind.get(e.kind, 0) + 1
        m: dict[str, Any] = {
            "horizon_s": self.horizon,
            "risky_time_s": round(ex.risky, 6),
            "unmonitored_exposure_s": round(ex.exposure, 6),
            "switches": ex.switches,
            "blind_time_per_switch_s": round(sum(ex.blind) / len(ex.blind), 6) if ex.blind else 0.0,
            "blind_time_max_s": round(max(ex.blind), 6) if ex.blind else 0.0,
            "reactions": self.reactions,
            "starts": self.starts,
            "start_failures": self.start_failures,
            "stops": self.stops,
            "migrations": self.migrations,
            "upgrades": self.upgrades,
            "upgrades_failed": self.upgrades_failed,
            "upgrade_blind_s": round(self.upgrade_blind, 6),
            "errors": dict(sorted(by_kind.items())),
            "violations": len(self.violations),
            "memory_peak_mb": {p: round(v, 3) for p, v in self.memory.peak.items()},
            "overcommit_s": {p: round(v, 6) for p, v in sorted(self.memory.over.items()) if v > 0},
            "alarms": len(self.alarms),
            "signals": self.signals_on,
        }
        if self.world.changes or self.world.random_changes is not None or self.world.lease is not None:
            m["requirement_changes"] = self.requirement_changes
            m["leases"] = self.leases
            m["leased_s"] = round(self.leased_s, 6)
        if self.signals_on:
            # graphs that cannot alarm: never counted as monitoring (see _activate)
            m["no_signal_model"] = {g: list(kinds) for g, kinds in self.world.no_signal_model(self.model.graphs).items()}
            m.update(slip_metrics(self.slips, self.alarms))
            m["samples"] = dict(self.bank.samples) if self.bank is not None else {}
        else:
            m["slips_injected"] = len(self.slips)
        return m


@dataclass
class _Reaction:
    """What the deployer process books during one reaction."""

    slots: tuple[tuple[str, ...], ...]
    raised: list[str] = field(default_factory=list)
    stopped_here: dict[str, str] = field(default_factory=dict)
    stopped_at: dict[str, float] = field(default_factory=dict)  # wanted slot members stopped in this reaction
    tried: set[str] = field(default_factory=set)  # graphs whose start failed in this reaction


def _merge_windows(ws: list[tuple[float, float]]) -> tuple[list[float], list[float]]:
    """Sorted, merged windows as ``(starts, ends)``."""
    lo: list[float] = []
    hi: list[float] = []
    for a, b in sorted(ws):
        if hi and a <= hi[-1]:
            hi[-1] = max(hi[-1], b)
        else:
            lo.append(a)
            hi.append(b)
    return lo, hi


def simulate(scenario: Scenario, deployer: str = "desmon", seed: int = 0, **kw: Any) -> RunResult:
    """Run ``scenario`` in the SimPy world and return the result."""
    return SimWorld(scenario, deployer=deployer, seed=seed, **kw).run()
