"""The Control infrastructure of one robot's SimPy world: it starts and stops detector
instances on the physical facts and runs them.

Each ``start`` waits the platform's start latency and then succeeds or fails by the
world's failure model only (platform down, scripted or seeded random failure, the one
Control semantics of :class:`desmon.deployment.control.ControlRules`). It does *not*
check Capacity -- that is the core's decision: a start the deployer asks for on a
platform without room really over-commits it, and the audit (``no-overcommit``)
reports it. A success starts the detector process (consuming its spec's
``consumption()``) and ``record_start``\\ s the DEPLOYED_ON edge; ``stop`` frees the
memory and records the DEPLOYMENT_HISTORY.

Detector processes consume every sample of their devices since the last wake-up, in
one vectorised call, on the wake-up grid of :meth:`GroundTruth.next_wake
<desmon.sim.facts.GroundTruth.next_wake>`. A platform going down halts its instances
and silences its devices; one coming back restarts them (the supervisor).
"""

from __future__ import annotations

import math
import random
from typing import Any, Callable

import simpy

from desmon.deployment.control import ControlRules
from desmon.detectors.base import Alarm
from desmon.model.events import DeviceEvent, Event, LoadChange
from desmon.repository.facts import record_start, record_stop
from desmon.repository.store import Repository
from desmon.sim.facts import GroundTruth, Instance, PhysicalFacts
from desmon.sim.metrics import Exposure, MemoryMeter
from desmon.sim.sensors import DetectorAdapter
from desmon.sim.trace import Trace
from desmon.sim.world import World, can_detect, detector_plans

__all__ = ["Infrastructure", "SCRIPTED_FAILURE", "RANDOM_FAILURE"]

#: why a start the Control rules allowed failed: the world's start-failure model (scripted,
#: or at random), the environment's doing as the checker's ``start_failures`` choices are
SCRIPTED_FAILURE = "scripted start failure"
RANDOM_FAILURE = "start failed"


#: seconds from a slip's onset to the alarm of a detector with a given rate
GIVEN_LATENCY = 0.1


class Infrastructure:
    """Control (start, stop) on the physical facts, and the detector instances' lives."""

    def __init__(
        self, env: simpy.Environment, world: World, repo: Repository, trace: Trace, facts: PhysicalFacts, truth: GroundTruth,
        rules: Any, exposure: Exposure, memory: MemoryMeter, *, seed: int, signals: bool, every_alarm: bool = True,
    ) -> None:
        self.env = env
        self.world = world
        self.repo = repo
        self.trace = trace
        self.facts = facts
        self.truth = truth
        #: the one Control semantics (desmon.deployment.control), on the physical facts
        self.rules = rules
        self.exposure = exposure
        self.memory = memory
        self.signals = signals
        #: False: the detectors run only on the spans of an activation up to one near a slip
        #: (:meth:`feed`), where an alarm could detect it; none reads the alarms elsewhere
        self.every_alarm = every_alarm
        self.starts = self.start_failures = self.stops = 0
        self.attempts: dict[tuple[str, str], int] = {}
        self.rng_start = random.Random(f"{seed}:start")
        #: exponential timing (World.timing): start latencies drawn from here
        self.rng_latency = random.Random(f"{seed}:latency")
        self.rng_warmup = random.Random(f"{seed}:warmup")
        #: the draws of the detectors whose rate World.detection_rates gives
        self.rng_given = random.Random(f"{seed}:given")
        #: graph -> its detector plan, or None: it cannot detect (desmon.sim.world.detector_plans)
        self.plans = detector_plans(world, facts.model)
        facts.detects = can_detect(world, self.plans)
        self.alarms: list[Alarm] = []
        #: when each platform last hosted an instance (a lease ends once it stayed idle)
        self.last_busy: dict[str, float] = {}
        self._pending_ready: list[Instance] = []
        self._wiring: dict[tuple[str, str], dict[str, tuple[str, ...]]] = {}  # (graph, platform) -> devices_for
        # (graph, platform) -> (readability version, specification, refusal): see _rules_refusal
        self._refusals: dict[tuple[str, str], tuple[int, Any, str]] = {}

    # ------------------------------------------------------------------ physical changes
    def mem(self, p: str) -> None:
        self.memory.set(p, self.env.now, self.facts.used(p))

    def apply_physical(self, ev: Event, t: float) -> None:
        """A load or device change, on the facts and on the signals."""
        facts = self.facts
        bank = self.truth.bank
        if isinstance(ev, LoadChange) and ev.resource == "memory":
            facts.load[ev.platform] = ev.amount
        elif isinstance(ev, DeviceEvent):
            facts.dev_ok[ev.device] = ev.working
            if bank is not None and facts.up[facts.host[ev.device]]:  # else silent (until it is up)
                (bank.repair if ev.working else bank.fail)(ev.device, t)

    def inputs_change(self, readers: list[Instance], now: float, change: Callable[[], None]) -> None:
        """Apply ``change`` to the physical world; instances on other platforms reading the
        affected devices (``readers``) are fed up to ``now`` first, re-activated when their
        inputs come back, and reported invalid when they lose them."""
        facts = self.facts
        before = {id(i): facts.alive(i) for i in readers}
        ok_before = {id(i): facts.inputs_ok(i) for i in readers}
        for inst in readers:
            self.feed(inst, now)
        change()
        for inst in readers:
            if not ok_before[id(inst)] and facts.inputs_ok(inst) and facts.up[inst.platform]:
                self.activate(inst, now)  # input back: re-tare / warm up
            elif before[id(inst)] and not facts.alive(inst):
                self.trace.emit(now, "invalid", graph=inst.graph, platform=inst.platform, reason="sensor_failure")

    def platform_flip(self, platform: str, up: bool, now: float) -> None:
        """A platform goes down (its instances halt, its devices go silent) or comes back
        (the supervisor restarts its instances, its working devices stream again)."""
        facts = self.facts
        for inst in [i for i in facts.instances.values() if i.platform == platform]:
            if up:
                inst.fed = now
                inst.halted = False
                self.activate(inst, now)  # the supervisor restarts it on reboot
            else:
                alive = facts.alive(inst)
                self.feed(inst, now)
                inst.halted = True
                inst.valid_from = math.inf
                if inst.adapter is not None:
                    inst.adapter.deactivate()
                if alive:
                    self.trace.emit(now, "invalid", graph=inst.graph, platform=inst.platform, reason="platform_crash")
        facts.up[platform] = up
        bank = self.truth.bank
        if bank is not None:
            for d in facts.hosted[platform]:
                if facts.dev_ok[d.name]:
                    (bank.repair if up else bank.fail)(d.name, now)
        self.mem(platform)

    def follow_consumption(self, graph: str, spec: Any) -> None:
        """What ``graph`` consumes follows ``spec``, its current specification, running
        instances included."""
        memory = dict(spec.consumption()).get("memory", 0.0) if spec is not None else 0.0
        self.facts.consumes[graph] = memory
        for inst in self.facts.instances.values():
            if inst.graph == graph:  # a running instance now needs what its spec says
                inst.memory = memory
                self.mem(inst.platform)

    # ------------------------------------------------------------------ Control
    def devices_for(self, graph: str, platform: str) -> dict[str, tuple[str, ...]]:
        """Stream -> the devices ``graph`` reads on ``platform``: one dict per pair, which
        nobody changes (instances share it; the facts memoise on its identity)."""
        out = self._wiring.get((graph, platform))
        if out is None:
            out = self._wiring[(graph, platform)] = {}
            for kind, devices in self.rules.input_devices(graph, platform):
                devs = tuple(d.name for d in devices)
                stream = self.world.signal_of(kind) or kind
                out[stream] = out.get(stream, ()) + devs
        return out

    def start(self, graph: str, platform: str):  # type: ignore[no-untyped-def]
        """Control.start: latency, then success or failure; returns the outcome."""
        env = self.env
        instances = self.facts.instances
        if (graph, platform) in instances:
            return True
        n = self.attempts[(graph, platform)] = self.attempts.get((graph, platform), 0) + 1
        latency = self.world.latency(platform)
        ready_at = env.now
        if latency and self.world.timing == "exponential":  # decided at once, ready after the latency
            ready_at += self.rng_latency.expovariate(1.0 / latency)
        elif latency:
            self.exposure.advance(env.now)
            self.facts.pending[(graph, platform)] = self.devices_for(graph, platform)
            try:
                yield env.timeout(latency)
            finally:
                self.exposure.advance(env.now)
                self.facts.pending.pop((graph, platform), None)
        reason = self._refusal(graph, platform, n)
        if reason:
            self.start_failures += 1
            return reason
        if (graph, platform) in instances:
            return True
        self.exposure.advance(env.now)
        streams = self.devices_for(graph, platform)
        adapter = DetectorAdapter(frozenset(streams), graph) if self.signals else None
        inst = Instance(graph, platform, self.facts.consumes.get(graph, 0.0), streams, adapter, env.now, ready_at=ready_at)
        self.activate(inst, env.now)
        instances[(graph, platform)] = inst
        self.last_busy[platform] = env.now
        self.starts += 1
        record_start(self.repo, graph, platform)
        self.mem(platform)
        if not self.flush_ready():  # a ready instance reported: its check was this one (nothing changed since)
            self.exposure.check(env.now)
        if adapter is not None and adapter.det is not None:
            inst.proc = env.process(self._detector(inst))
        elif self.signals and self.world.given_rate(graph) is not None:
            inst.proc = env.process(_given_alarms(self, inst, self.world.given_rate(graph)))
        return True

    def _refusal(self, graph: str, platform: str, n: int) -> str:
        """Why the ``n``-th start of ``graph`` on ``platform`` fails ("": it succeeds)."""
        reason = self._rules_refusal(graph, platform)
        if reason:
            return reason
        failure = self.world.start_failure
        if (graph, platform, n) in failure.script:
            return SCRIPTED_FAILURE
        if failure.probability and self.rng_start.random() < failure.probability:
            return RANDOM_FAILURE
        return ""

    def _rules_refusal(self, graph: str, platform: str) -> str:
        """The Control rules' refusal of ``graph`` on ``platform`` ("": none). Plain
        :class:`ControlRules` read only the facts' platform states (the same while the
        readability version stands), the graph's specification (the same object while
        unchanged) and pure checks: their answer is kept on those two; other rules (a
        fleet's admission control) are asked every time."""
        rules = self.rules
        if type(rules) is not ControlRules or rules.spec_of is None:
            return rules.start_refusal(graph, platform, self.facts.state) or ""
        spec = rules.spec_of(graph)
        version = self.facts.readability
        hit = self._refusals.get((graph, platform))
        if hit is not None and hit[0] == version and hit[1] is spec:
            return hit[2]
        reason = rules.start_refusal(graph, platform, self.facts.state) or ""
        self._refusals[(graph, platform)] = (version, spec, reason)  # the entry holds the spec its test names
        return reason

    def stop(self, graph: str, platform: str) -> bool:
        """Control.stop: free the memory, end the process, record DEPLOYMENT_HISTORY."""
        instances = self.facts.instances
        inst = instances.get((graph, platform))
        if inst is None:
            return False
        now = self.env.now
        self.exposure.advance(now)
        self.feed(inst, now)
        del instances[(graph, platform)]
        self.last_busy[platform] = now
        if inst.proc is not None and inst.proc.is_alive:
            inst.proc.interrupt("stop")
        if inst.adapter is not None:
            inst.adapter.deactivate()
        self.stops += 1
        record_stop(self.repo, graph, platform)
        self.mem(platform)
        self.exposure.check(now)
        return True

    # ------------------------------------------------------------------ detector instances
    def activate(self, inst: Instance, now: float) -> None:
        inst.fed = now
        inst.deferred.clear()  # (the detector forgets them: no slip was near)
        if not self.facts.detects.get(inst.graph, True):
            # what the graph reads has no signal model (World.no_signal_model): it runs
            # and uses memory, yet cannot detect a slip, so it never becomes valid and
            # never counts as watching, signals on or off (the run report lists it)
            inst.valid_from = math.inf
            inst.gen += 1
            if self.facts.instances.get((inst.graph, inst.platform)) is inst:  # its input is back: say so (no ready follows)
                self.trace.emit(now, "no_signal", graph=inst.graph, platform=inst.platform)
            return
        warm = self.warmup(inst.graph)
        # a start latency still running (exponential timing): the warm-up follows it
        wait = warm + max(0.0, inst.ready_at - now)
        inst.valid_from = now + wait
        inst.gen += 1
        if inst.adapter is not None:
            inst.adapter.activate(now)
        if wait > 0:
            gen = inst.gen
            self.env.timeout(wait).callbacks.append(lambda _ev: self._warmed(inst, gen))
        else:
            self._pending_ready.append(inst)  # valid at once: reported once it is registered

    def warmup(self, graph: str) -> float:
        """Seconds ``graph`` warms up after an activation: its detector's (force re-tare,
        tactile frames), signals on or off; under exponential timing drawn as an Erlang
        of ``World.phases`` phases with that mean, as ``desmon analyze`` models it."""
        plan = self.plans.get(graph)
        warm = plan.warmup if plan is not None else 0.0
        if warm and self.world.timing == "exponential":
            k = self.world.phases
            warm = sum(self.rng_warmup.expovariate(k / warm) for _ in range(k))
        return warm

    def _warmed(self, inst: Instance, gen: int) -> None:
        """A warm-up ended: report the instance ready if it is still that activation and alive."""
        now = self.env.now
        if inst.gen == gen and self.facts.instances.get((inst.graph, inst.platform)) is inst and self.facts.alive(inst):
            self.trace.emit(now, "ready", graph=inst.graph, platform=inst.platform)
        self.exposure.check(now)

    def flush_ready(self) -> bool:
        """Report the instances valid at once; True if there was one (each report ends
        with the exposure's check at this instant)."""
        reported = False
        while self._pending_ready:
            inst = self._pending_ready.pop(0)
            self._warmed(inst, inst.gen)
            reported = True
        return reported

    def _detector(self, inst: Instance):  # type: ignore[no-untyped-def]
        env = self.env
        next_wake = self.truth.next_wake
        try:
            while True:
                yield env.timeout(next_wake(env.now) - env.now)
                self.feed(inst, env.now)
        except simpy.Interrupt:
            return

    def feed(self, inst: Instance, t1: float) -> None:
        """Feed ``inst`` the samples of its devices up to ``t1``; record its alarms. Without
        :attr:`every_alarm`, a span far from every slip is kept (``inst.deferred``) and run,
        in order and with its bounds, before the activation's next span near one (the same
        state there, the same alarms); an activation that ends first never runs it."""
        t0 = inst.fed
        if t1 <= t0:
            return
        inst.fed = t1
        bank = self.truth.bank
        if inst.halted or inst.adapter is None or bank is None or not self.facts.up[inst.platform]:
            return
        if not self.every_alarm:
            if not self.truth.near_slip(t0, t1):
                inst.deferred.append((t0, t1))
                return
            for a, b in inst.deferred:
                _run_detector(self, inst, bank, a, b)
            inst.deferred.clear()
        _run_detector(self, inst, bank, t0, t1)


def _run_detector(infra: Infrastructure, inst: Instance, bank: Any, t0: float, t1: float) -> None:
    """Run ``inst``'s detector on its samples in ``[t0, t1)``; record its alarms."""
    for a in inst.adapter.feed(bank, t0, t1, inst.streams):  # type: ignore[union-attr]
        infra.alarms.append(a)
        infra.trace.emit(a.time, "alarm", detector=inst.graph, platform=inst.platform, direction=a.direction)


def _given_alarms(infra: Infrastructure, inst: Instance, rate: float):  # type: ignore[no-untyped-def]
    """A detector with a given rate (``World.detection_rates``), no signals: at each
    slip's onset, if it watches (valid, platform up, inputs readable), it alarms
    :data:`GIVEN_LATENCY` later, unless stopped by then, with probability ``rate``
    (one seeded draw per slip it watches)."""
    env = infra.env
    try:
        for slip in infra.truth.slips:
            if slip.time < env.now:
                continue
            yield env.timeout(slip.time - env.now)
            if inst.halted or inst.valid_from > env.now or not infra.facts.alive(inst):
                continue
            if infra.rng_given.random() < rate:
                yield env.timeout(GIVEN_LATENCY)  # stopped meanwhile: interrupted, no alarm
                infra.alarms.append(Alarm(env.now, inst.graph, slip.direction))
                infra.trace.emit(env.now, "alarm", detector=inst.graph, platform=inst.platform, direction=slip.direction)
    except simpy.Interrupt:
        return
