"""The typed world configuration a scenario passes as ``Scenario(world=...)``.

Everything the SimPy world needs beyond the model: the robot's task timeline (action
segments with durations, repeated or not), slips (scripted or a Poisson rate over the
time an object is in the hand), the fault schedule (scripted events or MTTF/MTTR per
component), start latency and start failure of the infrastructure, background load
(scripted or a bounded random walk), the context monitor's recognition delay and
heartbeat timeout, the horizon, and whether signals and detectors are simulated.

All of it is pure data; :func:`world_from_timeline` derives a world from a scenario's
scripted ``timeline`` for scenarios that do not declare one.
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass, field
from typing import Mapping, Sequence

from desmon.detectors.signals import Segment  # the one ground-truth segment type (re-exported here)
from desmon.errors import ScenarioError
from desmon.model.actions import ACTIONS, GRASP, IDLE, MOVE_BASE, RELEASE
from desmon.model.events import ActionChange, DeviceFail, DeviceRepair, LoadChange, PlatformDown, PlatformUp
from desmon.model.scenario import Scenario, TimedEvent

__all__ = [
    "Step",
    "Slip",
    "MTTF",
    "StartFailure",
    "LoadWalk",
    "World",
    "Segment",
    "world_from_timeline",
    "world_of",
    "expand_task",
    "draw_slips",
]


def _pos(what: str, v: float, *, zero: bool = True) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0 or (not zero and v == 0):
        raise ScenarioError(f"world: {what} = {v!r} must be a {'non-negative' if zero else 'positive'} finite number of seconds")
    return float(v)


@dataclass(frozen=True, slots=True)
class Step:
    """One action of the task: the robot is in context ``action`` for ``duration`` seconds."""

    action: str
    duration: float

    def __post_init__(self) -> None:
        if self.action not in ACTIONS:
            raise ScenarioError(f"world: task action {self.action!r} unknown: use one of {', '.join(ACTIONS)}")
        _pos(f"duration of {self.action}", self.duration, zero=False)


@dataclass(frozen=True, slots=True)
class Slip:
    """A scripted slip: object motion starts at ``time``; ``direction`` up/down; ``kind`` pulled/gravitational."""

    time: float
    direction: str = "down"
    kind: str = "pulled"

    def __post_init__(self) -> None:
        _pos("slip time", self.time)
        if self.direction not in ("up", "down") or self.kind not in ("pulled", "gravitational"):
            raise ScenarioError(f"world: slip at {self.time}: direction must be up/down and kind pulled/gravitational")


@dataclass(frozen=True, slots=True)
class MTTF:
    """Stochastic breakdowns of ``component`` (a device or a platform): exponential
    time to failure with mean ``mttf`` s, exponential repair with mean ``mttr`` s."""

    component: str
    mttf: float
    mttr: float

    def __post_init__(self) -> None:
        _pos(f"mttf of {self.component}", self.mttf, zero=False)
        _pos(f"mttr of {self.component}", self.mttr, zero=False)


@dataclass(frozen=True, slots=True)
class StartFailure:
    """How ``start`` fails: with ``probability`` per attempt, and/or scripted: each
    ``(graph, platform, n)`` in ``script`` makes the n-th attempt (1-based) of starting
    ``graph`` on ``platform`` fail."""

    probability: float = 0.0
    script: tuple[tuple[str, str, int], ...] = ()

    def __post_init__(self) -> None:
        if not 0.0 <= self.probability <= 1.0:
            raise ScenarioError(f"world: start failure probability {self.probability!r} must be in [0, 1]")


@dataclass(frozen=True, slots=True)
class LoadWalk:
    """Background ``memory`` load of ``platform`` as a random walk: every ``interval`` s
    it moves by ``drift`` plus N(0, ``sigma``) MB, clipped to [``low``, ``high``]."""

    platform: str
    start: float
    sigma: float
    interval: float
    low: float = 0.0
    high: float = math.inf
    drift: float = 0.0
    resource: str = "memory"

    def __post_init__(self) -> None:
        _pos(f"load walk interval of {self.platform}", self.interval, zero=False)
        if self.sigma < 0 or self.low > self.high:
            raise ScenarioError(f"world: load walk of {self.platform}: sigma must be >= 0 and low <= high")


@dataclass(frozen=True, slots=True)
class World:
    """The SimPy world's configuration (see the module docstring)."""

    task: tuple[Step, ...]
    horizon: float
    repeat: bool = False
    slips: tuple[Slip, ...] = ()
    #: stochastic slips per second of object-in-hand time (Poisson), on top of ``slips``
    slip_rate: float = 0.0
    #: scripted device / platform events (DeviceFail, DeviceRepair, PlatformDown, PlatformUp)
    faults: tuple[TimedEvent, ...] = ()
    stochastic_faults: tuple[MTTF, ...] = ()
    #: seconds from Control.start to the detector running: a default and per-platform overrides
    start_latency: float = 0.0
    platform_latency: tuple[tuple[str, float], ...] = ()
    start_failure: StartFailure = field(default_factory=StartFailure)
    #: scripted LoadChange events
    loads: tuple[TimedEvent, ...] = ()
    load_walks: tuple[LoadWalk, ...] = ()
    #: seconds the context monitor needs to recognise a new action context
    recognition_delay: float = 0.0
    #: seconds until a missing device / platform heartbeat is noticed (and a repair seen)
    heartbeat_timeout: float = 0.0
    #: simulate sensor signals and run the detectors on them
    signals: bool = True
    #: sim seconds of samples a detector consumes per SimPy wake-up while a slip is under way
    block: float = 0.5
    #: sim seconds per wake-up in quiet stretches (no ground-truth slip within
    #: [-2, +2] s); detector output is chunking-invariant, so this only decides how late
    #: a false alarm's record is written to the trace (``<= block`` disables it)
    quiet_block: float = 30.0
    #: device kind -> signal stream ('wrench' or 'tactile'); unknown kinds are guessed from the name
    signal_kinds: tuple[tuple[str, str], ...] = (("force_sensor", "wrench"), ("tactile_pad", "tactile"), ("tactile_array", "tactile"))
    #: how the robot holds the object when it is handed over (slips in release are pulls)
    description: str = ""

    def __post_init__(self) -> None:
        if not self.task:
            raise ScenarioError("world: the task is empty; give at least one Step(action, duration)")
        _pos("horizon", self.horizon, zero=False)
        _pos("start latency", self.start_latency)
        for p, v in self.platform_latency:
            _pos(f"start latency of {p}", v)
        _pos("recognition delay", self.recognition_delay)
        _pos("heartbeat timeout", self.heartbeat_timeout)
        _pos("block", self.block, zero=False)
        _pos("quiet block", self.quiet_block, zero=False)
        if self.slip_rate < 0:
            raise ScenarioError(f"world: slip_rate {self.slip_rate!r} must be >= 0")
        for te in self.faults:
            if not isinstance(te.event, (DeviceFail, DeviceRepair, PlatformDown, PlatformUp)):
                raise ScenarioError(f"world: fault {te.event} is not a device or platform event")
        for te in self.loads:
            if not isinstance(te.event, LoadChange):
                raise ScenarioError(f"world: load event {te.event} is not a LoadChange")

    def latency(self, platform: str) -> float:
        for p, v in self.platform_latency:
            if p == platform:
                return v
        return self.start_latency

    def signal_of(self, kind: str) -> str | None:
        for k, s in self.signal_kinds:
            if k == kind:
                return s
        low = kind.lower()
        if "force" in low or "wrench" in low:
            return "wrench"
        if "tactile" in low:
            return "tactile"
        return None

    def check_against(self, scenario: Scenario) -> None:
        """Names in the world must exist in the model."""
        model = scenario.model
        devices = {d.name for d in model.devices}
        platforms = {p.name for p in model.platforms}
        for te in self.faults + self.loads:
            ev = te.event
            name = getattr(ev, "device", None) or getattr(ev, "platform", None)
            if name not in devices | platforms:
                raise ScenarioError(f"world of {scenario.name!r}: {ev} names unknown component {name!r}")
        for m in self.stochastic_faults:
            if m.component not in devices | platforms:
                raise ScenarioError(
                    f"world of {scenario.name!r}: MTTF for unknown component {m.component!r} "
                    f"(devices {sorted(devices)}, platforms {sorted(platforms)})"
                )
        for w in self.load_walks:
            if w.platform not in platforms:
                raise ScenarioError(f"world of {scenario.name!r}: load walk on unknown platform {w.platform!r}")
        for p, _v in self.platform_latency:
            if p not in platforms:
                raise ScenarioError(f"world of {scenario.name!r}: start latency for unknown platform {p!r}")


def expand_task(world: World, horizon: float) -> tuple[Segment, ...]:
    """The ground-truth segments up to ``horizon`` (the task once, or repeated); each
    segment's ``context`` is the step's action."""
    out: list[Segment] = []
    t = 0.0
    while t < horizon:
        for step in world.task:
            if t >= horizon:
                break
            out.append(Segment(step.action, float(t), float(step.duration)))
            t += step.duration
        if not world.repeat:
            break
    return tuple(out)


def in_hand(segments: Sequence[Segment]) -> list[tuple[float, float, str]]:
    """Segments during which an object is in the hand (as MissionSignals renders episodes)."""
    out = []
    holding = False
    prev_end = 0.0
    for s in segments:
        if s.start > prev_end + 1e-9:
            holding = False
        if s.context == IDLE:
            holding = False
        elif s.context == GRASP or not holding:
            holding = True
        if holding and s.context != IDLE:
            out.append((s.start, s.end, s.context))
        if s.context == RELEASE:
            holding = False
        prev_end = s.end
    return out


def draw_slips(world: World, segments: Sequence[Segment], seed: int) -> tuple[Slip, ...]:
    """Scripted slips plus Poisson slips over in-hand time, from their own seeded stream."""
    slips = list(world.slips)
    if world.slip_rate > 0:
        rng = random.Random(f"{seed}:slips")
        for start, end, action in in_hand(segments):
            lo, hi = start + 0.4, end - 1.2
            if hi <= lo:
                continue
            t = lo + rng.expovariate(world.slip_rate)
            while t < hi:
                if action == RELEASE:
                    slips.append(Slip(round(t, 4), "up", "pulled"))
                elif action == MOVE_BASE:
                    slips.append(Slip(round(t, 4), "down", "gravitational"))
                else:
                    slips.append(Slip(round(t, 4), "down", "pulled"))
                t += 2.5 + rng.expovariate(world.slip_rate)
    return tuple(sorted(slips, key=lambda s: s.time))


def world_from_timeline(scenario: Scenario) -> World:
    """A world that plays a scenario's scripted ``timeline``: action changes become task
    steps, device / platform events become scripted faults, load changes scripted loads."""
    actions = [(te.time, te.event.action) for te in scenario.timeline if isinstance(te.event, ActionChange)]
    last = scenario.timeline[-1].time if scenario.timeline else 0.0
    horizon = last + 5.0
    if not actions or actions[0][0] > 0:
        actions.insert(0, (0.0, IDLE))
    steps = []
    for i, (t, a) in enumerate(actions):
        end = actions[i + 1][0] if i + 1 < len(actions) else horizon
        if end > t:
            steps.append(Step(a, end - t))
    faults = tuple(te for te in scenario.timeline if isinstance(te.event, (DeviceFail, DeviceRepair, PlatformDown, PlatformUp)))
    loads = tuple(te for te in scenario.timeline if isinstance(te.event, LoadChange))
    return World(task=tuple(steps), horizon=horizon, faults=faults, loads=loads, signals=False)


def world_of(scenario: Scenario) -> World:
    """The scenario's world (checked against its model), or one derived from its timeline."""
    w = scenario.world
    if w is None:
        w = world_from_timeline(scenario)
    elif isinstance(w, Mapping):
        raise ScenarioError(f"scenario {scenario.name!r}: world must be a desmon.sim.world.World, not a dict")
    elif not isinstance(w, World):
        raise ScenarioError(f"scenario {scenario.name!r}: world is a {type(w).__name__}; build a desmon.sim.world.World")
    w.check_against(scenario)
    return w
