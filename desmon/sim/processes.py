"""The processes of one robot's SimPy world: small generator functions over the robot's
parts (:class:`desmon.sim.robot.RobotParts`), and the steps they take.

* **Robot** (:func:`robot`) walks the task's ground-truth segments; each new action
  becomes a gripper / base observation that the context monitor interprets
  (``deployment.monitor.interpret``) after the recognition delay (:func:`recognise`). An
  action the gripper does not show (``rotate_*``, a model's own actions) is recognised
  directly, after the same delay.
* **Context monitor** (:func:`insert`, :func:`notice`) inserts facts into the repository
  through the core's Insert port (context, HAS_DEVICE loss / repair noticed after the
  heartbeat timeout, platform up / down, background load).
* **Fault injector** (:func:`fault`, :func:`scripted_faults`, :func:`stochastic_faults`)
  fails and repairs devices and platforms (script or MTTF / MTTR); **load** processes
  (:func:`scripted_loads`, :func:`load_walk`) change the background memory load.
* **Run-time changes** (:func:`change`, :func:`scripted_changes`, :func:`random_changes`)
  and **leases** (:func:`maybe_lease`, :func:`lease`) of on-demand platforms.
"""

from __future__ import annotations

import random
from typing import TYPE_CHECKING, Any, Callable

from desmon.deployment.exposure import needs_table
from desmon.deployment.lease import lease_choice
from desmon.deployment.monitor import GripperObservation, interpret
from desmon.model.actions import GRASP, HOLD, IDLE, MOVE_BASE, RELEASE
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
from desmon.sim.trace import graph_resources

if TYPE_CHECKING:
    from desmon.sim.robot import RobotParts

__all__ = [
    "OBSERVATION", "apply_initial", "robot", "recognise", "recognise_later", "insert", "notice", "fault", "scripted_faults", "stochastic_faults",
    "set_load", "scripted_loads", "load_walk", "change", "follow_consumption", "scripted_changes", "random_changes",
    "maybe_lease", "lease", "markov_lease", "load_steps", "progress",
]

#: What the context monitor sees of gripper and base in each ground-truth action; an
#: action not listed here (rotate_*, a model's own actions) is recognised directly.
OBSERVATION = {
    GRASP: GripperObservation("closing"),
    RELEASE: GripperObservation("opening"),
    MOVE_BASE: GripperObservation("closed", base_moving=True),
    HOLD: GripperObservation("closed"),
    IDLE: GripperObservation("open", holding=False),
}


def apply_initial(parts: RobotParts) -> None:
    """The scenario's initial facts, silently (before Notify is wired)."""
    infra = parts.infra
    for ev in parts.scenario.initial:
        if isinstance(ev, PlatformEvent):
            infra.platform_flip(ev.platform, ev.up, 0.0)
        else:
            infra.apply_physical(ev, 0.0)
        parts.core.observe(ev)
        if isinstance(ev, RequirementChange):
            follow_consumption(parts, ev.graph)
    for p in parts.facts.up:
        parts.memory.set(p, 0.0, parts.facts.used(p))


# ---------------------------------------------------------------------- robot and context monitor
#: the pending recognition of the action context among :attr:`RobotParts.noticing`'s notices
#: (a component's is ("device" or "platform", its name): no name of a model can be it)
_CONTEXT = ("context", "")


def robot(parts: RobotParts):  # type: ignore[no-untyped-def]
    env = parts.env
    table = needs_table(parts.model)
    for seg in parts.truth.segments:
        if seg.start > env.now:
            yield env.timeout(seg.start - env.now)
        # what the definition asks of the TRUE context (desmon.deployment.exposure):
        # the selector's slots, kept apart (one covered slot does not hide an uncovered
        # one); the core's selector gives them for the recognised one
        parts.trace.emit(env.now, "action", action=seg.context, duration=seg.duration)
        parts.exposure.set_need(env.now, table[seg.context])
        if parts.world.timing == "exponential":
            if _CONTEXT not in parts.noticing:
                parts.noticing.add(_CONTEXT)
                env.process(recognise_latest(parts))
        elif parts.world.recognition_delay:
            recognise_later(parts, seg.context)
        else:
            env.process(recognise(parts, seg.context))
    segments = parts.truth.segments
    end = segments[-1].start + segments[-1].duration if segments else 0.0
    if end < parts.horizon:  # a task played once (World(repeat=False)) ends before the horizon:
        # the hand is empty from then on, as the slips and the signals have it (nothing is
        # risky or unmonitored); the monitor sees nothing new, so the deployment stays
        yield env.timeout(end - env.now)
        parts.exposure.set_need(env.now, table[IDLE])


def recognised_context(action: str) -> str:
    """The context the monitor makes of what the gripper and base show in ``action``."""
    obs = OBSERVATION.get(action)
    return interpret(obs) if obs is not None else action


def recognise(parts: RobotParts, action: str):  # type: ignore[no-untyped-def]
    if parts.world.recognition_delay:
        yield parts.env.timeout(parts.world.recognition_delay)
    insert(parts, ActionChange(recognised_context(action)))


def recognise_later(parts: RobotParts, action: str) -> None:
    """:func:`recognise` for a positive recognition delay, as a timeout whose callback
    inserts: no process of its own. Called from the robot's step, which a process made
    there would follow at once (its start is urgent), so the timeout is scheduled in the
    same order among the other events as the process's timeout would be; the process's
    end, which nobody waits for, is not an event any more."""
    action = recognised_context(action)
    parts.env.timeout(parts.world.recognition_delay).callbacks.append(lambda _ev: insert(parts, ActionChange(action)))


def recognise_latest(parts: RobotParts):  # type: ignore[no-untyped-def]
    """Exponential timing: after an exponential delay the monitor reports the action
    the robot performs *then* (one recognition pending at a time)."""
    if parts.world.recognition_delay:
        yield parts.env.timeout(parts.markov.expovariate(1.0 / parts.world.recognition_delay))
    parts.noticing.discard(_CONTEXT)
    insert(parts, ActionChange(recognised_context(parts.exposure.context)))


def insert(parts: RobotParts, ev: Event) -> None:
    """The context monitor writes a fact (Insert); Notify does the rest."""
    stim = parts.core.observe(ev)
    if not stim.empty:
        parts.trace.emit(parts.env.now, "fact", fact=str(ev))


def notice(parts: RobotParts, ev: Event):  # type: ignore[no-untyped-def]
    if parts.world.heartbeat_timeout:
        yield parts.env.timeout(parts.world.heartbeat_timeout)
    insert(parts, ev)


def notice_latest(parts: RobotParts, pending: tuple[str, str]):  # type: ignore[no-untyped-def]
    """Exponential timing: after an exponential delay the monitor reports the state the
    component of ``pending`` ("device" or "platform", name) is in *then* (one notice
    pending per component: a device and a platform of one name are two components)."""
    if parts.world.heartbeat_timeout:
        yield parts.env.timeout(parts.markov.expovariate(1.0 / parts.world.heartbeat_timeout))
    parts.noticing.discard(pending)
    facts = parts.facts
    kind, component = pending
    if kind == "device":
        insert(parts, DeviceRepair(component) if facts.dev_ok[component] else DeviceFail(component))
    elif parts.model.platform(component).on_demand:
        insert(parts, PlatformJoin(component) if facts.up[component] else PlatformLeave(component))
    else:
        insert(parts, PlatformUp(component) if facts.up[component] else PlatformDown(component))


# ---------------------------------------------------------------------- faults and loads
def fault(parts: RobotParts, ev: Event, source: str) -> None:
    """The fault injector changes the physical world; the monitor notices later."""
    env = parts.env
    now = env.now
    facts = parts.facts
    infra = parts.infra
    if isinstance(ev, DeviceEvent):
        if facts.dev_ok[ev.device] == ev.working:
            return
        parts.trace.emit(now, "fault", event=str(ev), source=source)
        parts.exposure.advance(now)
        readers = [i for i in facts.instances.values() if any(ev.device in devs for devs in i.streams.values())]
        infra.inputs_change(readers, now, lambda: infra.apply_physical(ev, now))
    else:
        up = ev.up
        if facts.up[ev.platform] == up:
            return
        parts.trace.emit(now, "fault", event=str(ev), source=source)
        parts.exposure.advance(now)
        hosted = {d.name for d in facts.hosted[ev.platform]}
        readers = [
            i for i in facts.instances.values()
            if i.platform != ev.platform and any(d in hosted for devs in i.streams.values() for d in devs)
        ]
        infra.inputs_change(readers, now, lambda: infra.platform_flip(ev.platform, up, now))
        parts.trace.emit(now, "platform", platform=ev.platform, up=up)
    if not infra.flush_ready():  # a ready instance reported: its check was this one (nothing changed since)
        parts.exposure.check(now)
    if parts.world.timing == "exponential":
        pending = ("device", ev.device) if isinstance(ev, DeviceEvent) else ("platform", ev.platform)
        if pending not in parts.noticing:
            parts.noticing.add(pending)
            env.process(notice_latest(parts, pending))
    else:
        env.process(notice(parts, ev))


def scripted(parts: RobotParts, timeline: tuple, apply: Callable[[Any], None]):  # type: ignore[no-untyped-def]
    """Apply each timed event of ``timeline`` at its time, until the horizon."""
    env = parts.env
    for te in timeline:
        if te.time >= parts.horizon:
            break
        if te.time > env.now:
            yield env.timeout(te.time - env.now)
        apply(te)


def scripted_faults(parts: RobotParts):  # type: ignore[no-untyped-def]
    return scripted(parts, parts.world.faults, lambda te: fault(parts, te.event, te.label or "script"))


def stochastic_faults(parts: RobotParts, component: str, mttf: float, mttr: float):  # type: ignore[no-untyped-def]
    """A component that fails after an exponential time of mean ``mttf`` and is repaired after
    one of mean ``mttr``, again and again; one broken from the start (the scenario's
    ``initial``) begins with its repair, as the chain of ``desmon analyze`` has it."""
    env = parts.env
    rng = random.Random(f"{parts.seed}:fault:{component}")
    is_dev = component in parts.facts.dev_ok
    broken = not parts.facts.dev_ok[component] if is_dev else not parts.facts.up[component]
    while True:
        if not broken:
            yield env.timeout(rng.expovariate(1.0 / mttf))
            fault(parts, DeviceFail(component) if is_dev else PlatformDown(component), "mttf")
        broken = False
        yield env.timeout(rng.expovariate(1.0 / mttr))
        fault(parts, DeviceRepair(component) if is_dev else PlatformUp(component), "mttr")


def set_load(parts: RobotParts, ev: LoadChange) -> None:
    if ev.resource == "memory":
        parts.facts.load[ev.platform] = ev.amount
        parts.infra.mem(ev.platform)
    parts.trace.emit(parts.env.now, "load", platform=ev.platform, resource=ev.resource, amount=ev.amount)
    insert(parts, ev)


def scripted_loads(parts: RobotParts):  # type: ignore[no-untyped-def]
    return scripted(parts, parts.world.loads, lambda te: set_load(parts, te.event))


def load_walk(parts: RobotParts, i: int):  # type: ignore[no-untyped-def]
    w = parts.world.load_walks[i]
    rng = random.Random(f"{parts.seed}:load:{w.platform}:{i}")
    x = w.start
    set_load(parts, LoadChange(w.platform, round(x, 1), w.resource))
    while True:
        yield parts.env.timeout(w.interval)
        x = min(w.high, max(w.low, x + w.drift + rng.gauss(0.0, w.sigma)))
        set_load(parts, LoadChange(w.platform, round(x, 1), w.resource))


def load_steps(parts: RobotParts, i: int):  # type: ignore[no-untyped-def]
    """A :class:`~desmon.sim.world.LoadSteps` walk: exponential gaps, a neighbouring level each."""
    w = parts.world.load_steps[i]
    rng = random.Random(f"{parts.seed}:loadsteps:{w.platform}:{i}")
    level = w.start
    set_load(parts, LoadChange(w.platform, level, w.resource))
    while True:
        yield parts.env.timeout(rng.expovariate(1.0 / w.mean_interval))
        level = rng.choice(w.neighbours(level))
        set_load(parts, LoadChange(w.platform, level, w.resource))


# ---------------------------------------------------------------------- run-time changes and leases
def change(parts: RobotParts, ev: Event, source: str, leased: bool = False) -> None:
    """A scripted or random run-time change: a requirement change is written by the
    context monitor at once (it is a decision of the robot's software, not a fault to
    be noticed); a platform joins or leaves like a platform that comes up or goes down.
    Leased time counts the lease's own joins (``leased``), not scripted ones."""
    now = parts.env.now
    if isinstance(ev, PlatformEvent):
        fault(parts, ev, source)
        if not leased:
            return
        if ev.up:
            parts.books.lease_joined(ev.platform, now)
        else:
            parts.books.lease_left(ev.platform, now)
        return
    parts.trace.emit(now, "change", event=str(ev), source=source)
    stim = parts.core.observe(ev)
    if stim.empty:
        return
    parts.books.requirement_changes += 1
    follow_consumption(parts, ev.graph)
    parts.trace.emit(now, "consumption", graph=ev.graph, resources=graph_resources(parts.query.deployment_information(ev.graph)))
    parts.trace.emit(now, "fact", fact=str(ev))
    parts.inbox.add(stim.changed_platforms, stim.specs_changed)


def follow_consumption(parts: RobotParts, graph: str) -> None:
    """What ``graph`` consumes follows its current specification, running instances included."""
    parts.infra.follow_consumption(graph, parts.query.deployment_information(graph))


def scripted_changes(parts: RobotParts):  # type: ignore[no-untyped-def]
    return scripted(parts, parts.world.changes, lambda te: change(parts, te.event, te.label or "script"))


def random_changes(parts: RobotParts):  # type: ignore[no-untyped-def]
    spec = parts.world.random_changes
    assert spec is not None
    rng = random.Random(f"{parts.seed}:changes")
    while True:
        yield parts.env.timeout(rng.expovariate(1.0 / spec.mean_interval))
        change(parts, rng.choice(spec.changes), "random")


def maybe_lease(parts: RobotParts, graph: str) -> None:
    """No acceptable platform for ``graph``: lease an on-demand platform on which it
    would be acceptable (:func:`desmon.deployment.lease.lease_choice`), unless one is
    already on its way."""
    spec = parts.world.lease
    assert spec is not None
    books = parts.books
    allowed = spec.platforms or tuple(p.name for p in parts.model.platforms if p.on_demand)
    absent = [p for p in allowed if not parts.facts.up[p] and p not in books.lease_requested]
    choice = lease_choice(parts.query, graph, absent) if absent else None
    if choice is None:
        return
    books.lease_requested.add(choice)
    books.leases += 1
    parts.trace.emit(parts.env.now, "lease", platform=choice, graph=graph)
    parts.env.process(lease(parts, choice) if parts.world.timing != "exponential" else markov_lease(parts, choice))


def lease(parts: RobotParts, platform: str):  # type: ignore[no-untyped-def]
    """A leased platform joins after its start-up delay and leaves once it has hosted
    nothing for the lease's ``idle_s``."""
    env = parts.env
    idle = parts.world.lease.idle_s  # type: ignore[union-attr]
    last_busy = parts.infra.last_busy
    yield env.timeout(parts.model.platform(platform).startup_s)
    change(parts, PlatformJoin(platform), "lease", leased=True)
    last_busy[platform] = env.now
    while True:
        busy = any(p == platform for _g, p in parts.facts.instances)
        wait = idle if busy else idle - (env.now - last_busy[platform])
        if not busy and wait <= 0:
            break
        yield env.timeout(max(wait, 1e-6))
    change(parts, PlatformLeave(platform), "lease", leased=True)
    parts.books.lease_requested.discard(platform)


def markov_lease(parts: RobotParts, platform: str):  # type: ignore[no-untyped-def]
    """Exponential timing: the platform joins after an exponential start-up (mean its
    ``startup_s``); then it leaves after an idle time of ``World.phases`` Erlang phases
    (mean the lease's ``idle_s``) counted only while it hosts nothing, as the chain of
    ``desmon analyze`` has it: phase ends come at exponential gaps of mean
    ``idle_s / phases``; one that finds the platform hosting counts nothing, and hosting
    since the last one starts the count over."""
    env = parts.env
    idle = parts.world.lease.idle_s  # type: ignore[union-attr]
    k = parts.world.phases
    rng = random.Random(f"{parts.seed}:lease:{platform}:{parts.books.leases}")
    startup = parts.model.platform(platform).startup_s
    yield env.timeout(rng.expovariate(1.0 / startup) if startup > 0 else 0.0)
    change(parts, PlatformJoin(platform), "lease", leased=True)
    last_busy = parts.infra.last_busy
    phase, tick = 0, env.now
    while phase < k:
        yield env.timeout(rng.expovariate(k / idle))
        if any(p == platform for _g, p in parts.facts.instances):
            phase = 0
        elif last_busy.get(platform, -1.0) > tick:  # it hosted something since the last phase end
            phase = 1
        else:
            phase += 1
        tick = env.now
    change(parts, PlatformLeave(platform), "lease", leased=True)
    parts.books.lease_requested.discard(platform)


def progress(parts: RobotParts, report: Callable[[float, float], None], steps: int = 20):  # type: ignore[no-untyped-def]
    """Call ``report(now, horizon)`` ``steps`` times a run."""
    env = parts.env
    step = parts.horizon / steps
    while True:
        yield env.timeout(step)
        report(env.now, parts.horizon)
