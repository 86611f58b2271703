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
from typing import Callable, Iterable, Mapping, Sequence

from desmon.detectors.signals import Segment  # the one ground-truth segment type (re-exported here)
from desmon.errors import ScenarioError
from desmon.model.actions import ACTIONS, GRASP, IDLE, RELEASE
from desmon.model.checks import (
    check_flag,
    check_items,
    check_name,
    check_names,
    check_number,
    check_pairs,
    exact,
    check_text,
    strict_init,
    suggest,
)
from desmon.model.events import Event, LoadChange, PlatformEvent, PlatformJoin, PlatformLeave, RequirementChange, Together, event_types
from desmon.model.graph import PerceptionGraph
from desmon.model.scenario import Scenario, TimedEvent, event_problem
from desmon.model.system import SystemModel, check_action
from desmon.sim.slip_kinds import check_slip_kinds
from desmon.sim.streams import DetectorPlan, default_signal_kinds, detector_plan, stream_names
from desmon.sim.world_components import check_components, check_initial_loads, refuse_together

__all__ = [
    "Step",
    "detector_plans",
    "can_detect",
    "Slip",
    "MTTF",
    "StartFailure",
    "LoadWalk",
    "LoadSteps",
    "RandomChanges",
    "Lease",
    "World",
    "Segment",
    "SIGNAL_STREAMS",
    "SIGNAL_KINDS",
    "world_from_timeline",
    "world_of",
    "expand_task",
    "like_segments",
    "in_hand",
    "draw_slips",
]

#: The signal streams desmon models (the stream classes of :mod:`desmon.sim.streams`, as of import).
SIGNAL_STREAMS = stream_names()
#: The default device kind -> signal stream mapping of ``World.signal_kinds`` (each
#: stream's ``device_kinds``). A kind that is not mapped has no signal model: with
#: signals on, a graph reading it runs but can never alarm, so it never counts as
#: monitoring (the run report lists it).
SIGNAL_KINDS: tuple[tuple[str, str], ...] = default_signal_kinds()


def _of_role(role: str) -> str:
    """The event classes of ``role`` (:attr:`desmon.model.events.Event.role`), for a message."""
    return ", ".join(cls.__name__ for cls in event_types() if cls.role == role)


def _seconds(what: str, v: object, *, zero: bool = True) -> float:
    return float(check_number(f"world: {what}", v, error=ScenarioError, positive=not zero, unit=" of seconds"))


@strict_init(ScenarioError)
@dataclass(frozen=True, slots=True)
class Step:
    """One action of the task: the robot is in context ``action`` for ``duration`` seconds.

    ``action`` is a built-in action or one the model declares; it is checked against the
    model when the scenario is built (:meth:`World.check_against`).
    """

    action: str
    duration: float

    def __post_init__(self) -> None:
        check_name("world: task action", self.action, error=ScenarioError)
        _seconds(f"duration of {self.action}", self.duration, zero=False)


@strict_init(ScenarioError)
@dataclass(frozen=True, slots=True)
class Slip:
    """A scripted slip: object motion starts at ``time``; ``direction`` up/down; ``kind`` pulled/gravitational."""

    time: float
    direction: str = "down"
    kind: str = "pulled"

    def __post_init__(self) -> None:
        _seconds("slip time", self.time)
        if self.direction not in ("up", "down") or self.kind not in ("pulled", "gravitational"):
            raise ScenarioError(
                f"world: slip at {self.time}: direction {self.direction!r} / kind {self.kind!r}: "
                "direction must be 'up' or 'down' and kind 'pulled' or 'gravitational'"
            )


@strict_init(ScenarioError)
@dataclass(frozen=True, slots=True)
class MTTF:
    """Stochastic breakdowns of ``component`` (a device or a platform): exponential
    time to failure with mean ``mttf`` s, exponential repair with mean ``mttr`` s."""

    component: str
    mttf: float
    mttr: float

    def __post_init__(self) -> None:
        check_name("world: MTTF component", self.component, error=ScenarioError)
        _seconds(f"mttf of {self.component}", self.mttf, zero=False)
        _seconds(f"mttr of {self.component}", self.mttr, zero=False)


@strict_init(ScenarioError)
@dataclass(frozen=True, slots=True)
class StartFailure:
    """How ``start`` fails: with ``probability`` per attempt, and/or scripted: each
    ``(graph, platform, n)`` in ``script`` makes the n-th attempt (1-based) of starting
    ``graph`` on ``platform`` fail."""

    probability: float = 0.0
    script: tuple[tuple[str, str, int], ...] = ()

    def __post_init__(self) -> None:
        check_number("world: start failure probability", self.probability, error=ScenarioError, high=1.0)
        example = "script=(('force_slip_detector', 'arm_pc', 1),)"
        entries = []
        for entry in check_items("world: start failure script", self.script, (tuple, list), error=ScenarioError, example=example):
            if len(entry) != 3:
                raise ScenarioError(f"world: start failure script entry {entry!r} is not (graph, platform, n): write {example}")
            graph, platform, n = entry
            check_name("world: start failure script graph", graph, error=ScenarioError)
            check_name("world: start failure script platform", platform, error=ScenarioError)
            check_number(f"world: start failure script attempt n of {graph!r} on {platform!r}", n, error=ScenarioError, integer=True)
            if n < 1:
                raise ScenarioError(
                    f"world: start failure script attempt n of {graph!r} on {platform!r} = {n!r}: attempts count from 1"
                )
            entries.append((graph, platform, int(n)))
        object.__setattr__(self, "script", tuple(entries))


@strict_init(ScenarioError)
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
        check_name("world: load walk platform", self.platform, error=ScenarioError)
        check_name(f"world: load walk of {self.platform!r} resource", self.resource, error=ScenarioError)
        where = f"world: load walk of {self.platform}"
        _seconds(f"load walk interval of {self.platform}", self.interval, zero=False)
        check_number(f"{where}: sigma", self.sigma, error=ScenarioError)
        check_number(f"{where}: low", self.low, error=ScenarioError)
        check_number(f"{where}: high", self.high, error=ScenarioError, infinite=True)
        check_number(f"{where}: drift", self.drift, error=ScenarioError, low=None)
        check_number(f"{where}: start", self.start, error=ScenarioError)
        if self.low > self.high:
            raise ScenarioError(f"{where}: low {self.low:g} > high {self.high:g}: give low <= high")
        if not self.low <= self.start <= self.high:
            raise ScenarioError(
                f"{where}: start {self.start:g} is outside [low, high] = [{self.low:g}, {self.high:g}]: "
                "start inside the range (the walk would jump to it at the first step)"
            )


@strict_init(ScenarioError)
@dataclass(frozen=True, slots=True)
class LoadSteps:
    """Background load of ``platform`` as a Markov walk over ``levels``: it starts at
    ``start`` and after exponential gaps of mean ``mean_interval`` seconds moves to a
    neighbouring level (either one with equal chance; from an end level, to its only
    neighbour). Unlike :class:`LoadWalk` it has a rate per level, so ``desmon analyze``
    can model it: the checker bounds' ``loads`` of the platform must list the same levels."""

    platform: str
    levels: tuple[float, ...]
    start: float
    mean_interval: float
    resource: str = "memory"

    def __post_init__(self) -> None:
        check_name("world: load steps platform", self.platform, error=ScenarioError)
        where = f"world: load steps of {self.platform}"
        check_name(f"{where}: resource", self.resource, error=ScenarioError)
        example = "levels=(600, 800)"
        if isinstance(self.levels, (str, bytes)) or not isinstance(self.levels, Sequence):
            raise ScenarioError(f"{where}: levels = {self.levels!r} is not a sequence of numbers: write {example}")
        levels = tuple(float(check_number(f"{where}: level", v, error=ScenarioError)) for v in self.levels)
        if len(levels) < 2:
            raise ScenarioError(f"{where}: levels {list(levels)} give the walk nowhere to go: give at least two, e.g. {example}")
        if any(b <= a for a, b in zip(levels, levels[1:])):
            raise ScenarioError(f"{where}: levels {[f'{v:g}' for v in levels]} are not strictly increasing: sort them and list each once")
        object.__setattr__(self, "levels", levels)
        check_number(f"{where}: start", self.start, error=ScenarioError)
        if float(self.start) not in levels:
            raise ScenarioError(f"{where}: start {self.start:g} is not one of its levels {[f'{v:g}' for v in levels]}: start on a level")
        object.__setattr__(self, "start", float(self.start))
        _seconds(f"load steps mean interval of {self.platform}", self.mean_interval, zero=False)

    def neighbours(self, level: float) -> tuple[float, ...]:
        """The levels the walk may move to from ``level``."""
        i = self.levels.index(level)
        return tuple(self.levels[j] for j in (i - 1, i + 1) if 0 <= j < len(self.levels))


#: the timings a World may run under (``World.timing``)
TIMINGS = ("fixed", "exponential")
#: the most Erlang phases of a task step (``World.phases``, ``desmon analyze --phases``)
MAX_PHASES = 64

#: the most random requirement changes a run's horizon may hold on average (:class:`RandomChanges`):
#: each is a reaction of the deployer; more would run for hours without a word
MAX_RANDOM_CHANGES = 100_000


@strict_init(ScenarioError)
@dataclass(frozen=True, slots=True)
class RandomChanges:
    """Random run-time requirement changes: after exponentially distributed gaps of mean
    ``mean_interval`` seconds, one of ``changes`` (uniformly, from the run's seed) happens."""

    changes: tuple[RequirementChange, ...]
    mean_interval: float

    def __post_init__(self) -> None:
        changes = check_items(
            "world: random changes", self.changes, RequirementChange, error=ScenarioError,
            example="(RequirementChange('combined', add=(Capacity('memory', 350),), remove=(Capacity('memory', 250),)),)",
        )
        if not changes:
            raise ScenarioError("world: random changes list no change: give at least one RequirementChange")
        if len(set(changes)) != len(changes):
            raise ScenarioError("world: random changes list a change twice (it would be drawn twice as often): list each once")
        object.__setattr__(self, "changes", changes)
        _seconds("random changes mean interval", self.mean_interval, zero=False)


@strict_init(ScenarioError)
@dataclass(frozen=True, slots=True)
class Lease:
    """On-demand capacity: when a wanted graph has no acceptable platform, the world
    leases an on-demand platform (of ``platforms``; all of the model's when empty) on
    which it would be acceptable; the platform joins after its ``startup_s`` and leaves
    once it has hosted nothing for ``idle_s`` seconds."""

    platforms: tuple[str, ...] = ()
    idle_s: float = 60.0

    def __post_init__(self) -> None:
        platforms = check_names("world: lease platforms", self.platforms, each="platform", error=ScenarioError, example="('edge',)")
        twice = [p for i, p in enumerate(platforms) if p in platforms[:i]]
        if twice:
            raise ScenarioError(f"world: lease platforms name {twice[0]!r} twice: give each once")
        object.__setattr__(self, "platforms", platforms)
        _seconds("lease idle_s", self.idle_s, zero=False)


@strict_init(ScenarioError)
@dataclass(frozen=True, slots=True)
class World:
    """The SimPy world's configuration (see the module docstring).

    Every field is checked when the world is built (types, ranges, order; scripted
    faults, loads and slips strictly before the horizon) and every name in it against
    the model when the scenario is built (:meth:`check_against`).
    """

    task: tuple[Step, ...]
    horizon: float
    repeat: bool = False
    slips: tuple[Slip, ...] = ()
    #: stochastic slips per second of object-in-hand time (Poisson), on top of ``slips``
    slip_rate: float = 0.0
    #: the kind of a random slip in each risky built-in action (a model's own action
    #: takes its ``like``'s): ``(action, direction, kind)`` triples; the default puts a
    #: pulled slip up in ``release`` (the hand-over), a gravitational slip down in
    #: ``move_base`` (the base accelerates), a pulled slip down elsewhere
    slip_kinds: tuple[tuple[str, str, str], ...] = ()
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
    #: background loads as Markov walks over levels (a rate per level: ``desmon analyze`` models them)
    load_steps: tuple[LoadSteps, ...] = ()
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
    #: device kind -> signal stream ('wrench' or 'tactile'), a tuple of pairs or a dict;
    #: it replaces :data:`SIGNAL_KINDS`. A kind not listed has no signal model (nothing is
    #: guessed from its name): with signals on, a graph reading it can never alarm and
    #: never counts as monitoring.
    signal_kinds: tuple[tuple[str, str], ...] = SIGNAL_KINDS
    #: graph -> the probability (0 < p <= 1) that it catches a slip while it watches, for
    #: a graph that reads a device kind with no signal model (a camera): a dict or pairs.
    #: Such a graph then watches once started (no warm-up) and alarms on a slip with that
    #: probability, in every engine; without a rate it cannot detect.
    detection_rates: tuple[tuple[str, float], ...] = ()
    description: str = ""
    #: scripted run-time changes: RequirementChange, PlatformJoin, PlatformLeave
    changes: tuple[TimedEvent, ...] = ()
    #: random requirement changes (Poisson), or None
    random_changes: RandomChanges | None = None
    #: leasing of on-demand platforms when nothing else fits, or None (never leased)
    lease: Lease | None = None
    #: "fixed": every delay as given; "exponential": the Markov world of ``desmon
    #: analyze`` (task steps Erlang-``phases`` with the step's duration as mean, the
    #: task repeating; recognition, heartbeat and start latency exponential with the
    #: given means; a start's outcome decided at once, the detector ready after its latency)
    timing: str = "fixed"
    #: Erlang phases of a task step under exponential timing (1: exponential)
    phases: int = 1

    def __post_init__(self) -> None:
        err = ScenarioError
        task = check_items("world: task", self.task, Step, error=err, example="task=(Step('grasp', 2.0), Step('hold', 3.0))")
        if not task:
            raise ScenarioError("world: the task is empty; give at least one Step(action, duration)")
        object.__setattr__(self, "task", task)
        self._check_scalars()
        self._check_scripted()
        _check_stochastic(self)
        kinds = check_pairs("world: signal_kinds", self.signal_kinds, error=err, example="{'force_sensor': 'wrench'}")
        streams = stream_names()
        for kind, stream in kinds:
            if stream not in streams:
                raise ScenarioError(
                    f"world: signal_kinds maps {kind!r} to {stream!r}{suggest(stream, streams)}, which is no signal "
                    f"stream: use one of {', '.join(streams)}"
                )
        object.__setattr__(self, "signal_kinds", kinds)
        object.__setattr__(self, "detection_rates", _check_rates(self.detection_rates))
        if not self.repeat:
            length = sum(float(s.duration) for s in task)  # (in floats: whole numbers past 1e308 would not print)
            if not math.isfinite(length):
                raise ScenarioError("world: the task's steps add up past 1e308 s, more than double precision counts: shorten its steps")
            if length > self.horizon + 1e-9:
                raise ScenarioError(
                    f"world: the task lasts {length:g} s but the horizon is {self.horizon:g} s, so its steps after "
                    f"{self.horizon:g} s would never happen: raise the horizon to {length:g}, shorten the task, "
                    "or use --until to stop a run early"
                )

    @property
    def repeats(self) -> bool:
        """Whether a run repeats the task: ``repeat=True``, or exponential timing (its task
        is the Markov world's cycle, whatever ``repeat`` says)."""
        return self.repeat or self.timing == "exponential"

    def _check_scalars(self) -> None:
        """The horizon, flags, description, latencies, delays, blocks, slip rate and start failure."""
        err = ScenarioError
        _seconds("horizon", self.horizon, zero=False)
        check_flag("world: repeat", self.repeat, error=err)
        check_flag("world: signals", self.signals, error=err)
        check_text("world: description", self.description, error=err)
        _seconds("start latency", self.start_latency)
        latencies = check_pairs("world: platform_latency", self.platform_latency, error=err, example="{'torso_pc': 0.4}")
        for p, v in latencies:
            _seconds(f"start latency of {p}", v)
        object.__setattr__(self, "platform_latency", latencies)
        _seconds("recognition delay", self.recognition_delay)
        if self.timing not in TIMINGS:
            raise ScenarioError(f"world: timing = {self.timing!r}: give one of {', '.join(repr(t) for t in TIMINGS)}")
        check_number("world: phases", self.phases, error=err, positive=True, integer=True, high=MAX_PHASES)
        if self.phases != 1 and self.timing != "exponential":
            raise ScenarioError(
                f"world: phases={self.phases} with timing={self.timing!r}: Erlang phases time the task steps under "
                "timing='exponential' (fixed steps last their durations); set timing='exponential' or drop phases"
            )
        _seconds("heartbeat timeout", self.heartbeat_timeout)
        _seconds("block", self.block, zero=False)
        _seconds("quiet block", self.quiet_block, zero=False)
        check_number("world: slip_rate", self.slip_rate, error=err, unit=" of slips per second of object-in-hand time")
        object.__setattr__(self, "slip_kinds", check_slip_kinds(self.slip_kinds))
        if not isinstance(self.start_failure, StartFailure):
            raise ScenarioError(f"world: start_failure = {self.start_failure!r} is not a StartFailure: write StartFailure(probability=0.02)")

    def _check_scripted_slips(self) -> None:
        """Scripted slips: of the right type, before the horizon, one at a moment, in the hand."""
        slips = check_items("world: slips", self.slips, Slip, error=ScenarioError, example="slips=(Slip(10.0, 'down', 'pulled'),)")
        for slip in slips:
            self._before_horizon(f"slip at t={slip.time:g}", slip.time)
        _one_slip_at_a_moment(slips)
        object.__setattr__(self, "slips", slips)
        if slips and all(step.action in ACTIONS for step in self.task):
            # with a model's own actions in the task this waits for check_against (the model says what they are like)
            self._check_slips(_builtin)

    def _check_scripted(self) -> None:
        """Scripted slips, faults and loads: the right types, before the horizon, in time order."""
        err = ScenarioError
        self._check_scripted_slips()
        example = "faults=(TimedEvent(20.0, DeviceFail('lwr_wrench')),)"
        faults = check_items("world: faults", self.faults, TimedEvent, error=err, example=example)
        refuse_together(faults, self.loads, self.changes)
        for te in faults:
            if te.event.role != "fault":
                raise ScenarioError(
                    f"world: fault {te.event} is not a device or platform event: faults are {_of_role('fault')} "
                    "(loads go in loads=, actions in task=)"
                )
        self._timed("faults", faults)
        object.__setattr__(self, "faults", faults)
        loads = check_items("world: loads", self.loads, TimedEvent, error=err, example="loads=(TimedEvent(10.0, LoadChange('arm_pc', 450)),)")
        for te in loads:
            if te.event.role != "load":
                raise ScenarioError(f"world: load event {te.event} is not a LoadChange: put it in faults= or the task")
        self._timed("loads", loads)
        object.__setattr__(self, "loads", loads)
        example = "changes=(TimedEvent(60.0, PlatformJoin('edge')),)"
        changes = check_items("world: changes", self.changes, TimedEvent, error=err, example=example)
        for te in changes:
            if te.event.role != "change":
                raise ScenarioError(
                    f"world: change {te.event} is not a run-time change: changes are {_of_role('change')} "
                    "(faults go in faults=, loads in loads=)"
                )
        self._timed("changes", changes)
        object.__setattr__(self, "changes", changes)
        if self.random_changes is not None and not isinstance(self.random_changes, RandomChanges):
            raise ScenarioError(f"world: random_changes = {self.random_changes!r} is not a RandomChanges: write RandomChanges(changes=(...), mean_interval=600)")
        if self.random_changes is not None and self.horizon / self.random_changes.mean_interval > MAX_RANDOM_CHANGES:
            least = self.horizon / MAX_RANDOM_CHANGES
            raise ScenarioError(
                f"world: random changes every {self.random_changes.mean_interval:g} s on average over the horizon of "
                f"{self.horizon:g} s are about {self.horizon / self.random_changes.mean_interval:,.0f} changes, more than the "
                f"{MAX_RANDOM_CHANGES:,} a run simulates; give mean_interval at least {least:.3g}"
            )
        if self.lease is not None and not isinstance(self.lease, Lease):
            raise ScenarioError(f"world: lease = {self.lease!r} is not a Lease: write Lease(idle_s=60)")
        self._check_one_master([(f"at t={te.time:g} in changes=", te.event) for te in changes])

    def _check_one_master(self, events: list[tuple[str, object]]) -> None:
        """A platform's presence has one master: the lease, or scripted joins and leaves
        (``events``: each with where it is written).

        Both at once give a run nobody can reason about (the script joins what the lease
        would release, or leaves what the lease hosts on; an initial join the simulation
        keeps for good, where the Markov chain leases it). A lease without platforms
        leases every on-demand platform, and only on-demand platforms join and leave.
        """
        if self.lease is None:
            return
        for where, ev in events:
            if isinstance(ev, PlatformEvent) and (not self.lease.platforms or ev.platform in self.lease.platforms):
                leased = f"lease=Lease(platforms={self.lease.platforms!r})" if self.lease.platforms else "lease=Lease() (every on-demand platform)"
                raise ScenarioError(
                    f"world: platform {ev.platform!r} has two masters of its presence: {leased} and the scripted "
                    f"'{ev}' {where}: let the lease drive it, or script its joins, not both "
                    "(drop lease=, name other platforms in Lease(platforms=...), or drop its PlatformJoin / PlatformLeave)"
                )

    def _check_slips(self, like: Callable[[str], str]) -> None:
        """A scripted slip needs an object in the hand (with signals off it would still
        count as injected); ``like`` maps each task action to the built-in it is like."""
        segments = expand_task(self, self.horizon)
        spans = in_hand(like_segments(segments, like))
        held = sum(max(0.0, min(b, self.horizon) - a) for a, b, _ in spans)
        if self.timing == "exponential" and held < self.horizon - 1e-9:
            empty = next(seg.context for seg in segments if not any(a <= seg.start < b for a, b, _ in spans))
            raise ScenarioError(
                f"world: scripted slips under timing='exponential': the task's steps move with the seed and {empty!r} has "
                "no object in the hand, so a slip at a fixed time may fall where nothing can slip; use slip_rate for "
                "slips while an object is in the hand, or timing='fixed'"
            )
        for slip in self.slips:
            if not any(a <= slip.time < b for a, b, _ in spans):
                during = next((seg.context for seg in segments if seg.start <= slip.time < seg.end), "?")
                raise ScenarioError(
                    f"world: slip at t={exact(slip.time)} falls in {during!r}, when no object is in the hand: "
                    "place slips between a grasp and its release"
                )

    def _before_horizon(self, what: str, t: float) -> None:
        if t >= self.horizon:
            raise ScenarioError(
                f"world: {what} is at or after the horizon {self.horizon:g} s, so it would never happen: "
                "move it before the horizon or raise the horizon"
            )

    def _timed(self, field_: str, events: tuple[TimedEvent, ...]) -> None:
        last = 0.0
        for te in events:
            self._before_horizon(f"{field_[:-1]} '{te.event}' at t={te.time:g}", te.time)
            if te.time < last:
                raise ScenarioError(
                    f"world: {field_[:-1]} '{te.event}' at t={te.time:g} comes before t={last:g}: sort the {field_} by time"
                )
            last = te.time

    def latency(self, platform: str) -> float:
        for p, v in self.platform_latency:
            if p == platform:
                return v
        return self.start_latency

    def signal_of(self, kind: str) -> str | None:
        """The signal stream of device ``kind`` (``signal_kinds``), or None: no signal model."""
        for k, s in self.signal_kinds:
            if k == kind:
                return s
        return None

    def given_rate(self, graph: str) -> float | None:
        """The detection rate ``detection_rates`` gives ``graph``, or None."""
        return dict(self.detection_rates).get(graph)

    def no_signal_model(self, graphs: Iterable[PerceptionGraph]) -> dict[str, tuple[str, ...]]:
        """Graph -> the device kinds it reads that have no signal model (graphs with none left out)."""
        out: dict[str, tuple[str, ...]] = {}
        for g in graphs:
            missing = tuple(k for k in g.device_kinds if self.signal_of(k) is None)
            if missing:
                out[g.name] = missing
        return out

    def check_against(self, scenario: Scenario) -> None:
        """Every name in the world must exist in the scenario's model."""
        model = scenario.model
        where = f"world of {scenario.name!r}"
        for step in self.task:
            check_action(model, step.action, where=where, what="task action", error=ScenarioError)
        if self.slips:
            self._check_slips(model.like)
        changes = [te.event for te in self.changes] + list(self.random_changes.changes if self.random_changes else ())
        changes += [ev for ev in scenario.initial if isinstance(ev, RequirementChange)]  # (what a change may remove, as Bounds takes it)
        for te in self.faults + self.loads + self.changes:
            problem = event_problem(te.event, model, changes)
            if problem is not None:
                raise ScenarioError(f"{where}: at t={te.time:g}: {problem}")
        _check_runtime_changes(self, model, where, changes)
        self._check_one_master([("in the scenario's initial=", ev) for ev in scenario.initial if isinstance(ev, (PlatformJoin, PlatformLeave))])
        check_components(self, scenario, where)
        check_initial_loads(self, scenario, where)
        _check_rates_against(self, model, where)
        kinds = sorted({d.kind for d in model.devices})
        for kind, stream in self.signal_kinds:
            if kind not in kinds and (kind, stream) not in SIGNAL_KINDS:
                raise ScenarioError(
                    f"{where}: signal_kinds maps {kind!r}, which no device is{suggest(kind, kinds)}: fix the kind (kinds: {', '.join(kinds)})"
                )


def _one_slip_at_a_moment(slips: tuple[Slip, ...]) -> None:
    times = [s.time for s in slips]
    twice = sorted({t for t in times if times.count(t) > 1})
    if twice:
        raise ScenarioError(
            f"world: slips lists {times.count(twice[0])} slips at t={twice[0]:g}: the object in the hand starts to slip once "
            "at a moment (each would count as injected, and one alarm detect them all); give each slip its own time"
        )


def _check_load_masters(world: World) -> None:
    """A platform's load of a resource has one master: scripted LoadChanges, or a load
    walk or load steps, not both (the walk's next step would overwrite a scripted load
    at once, and the scripted one never take effect)."""
    walked = {(w.platform, w.resource): "load walk" for w in world.load_walks}
    walked.update({(w.platform, w.resource): "load steps" for w in world.load_steps})
    for te in world.loads:
        ev = te.event
        what = walked.get((ev.platform, ev.resource))
        if what is not None:
            raise ScenarioError(
                f"world: the {ev.resource} load of {ev.platform!r} has two masters: a {what} and the scripted '{ev}' at "
                f"t={te.time:g} in loads=: let the {what} drive it, or script it, not both"
            )


def _check_stochastic(world: World) -> None:
    """MTTF entries (one per component) and load walks (one per platform and resource)."""
    err = ScenarioError
    mttfs = check_items("world: stochastic_faults", world.stochastic_faults, MTTF, error=err, example="(MTTF('lwr_wrench', mttf=3600, mttr=120),)")
    seen: set[str] = set()
    for m in mttfs:
        if m.component in seen:
            raise ScenarioError(f"world: two MTTF entries for {m.component!r}: give one per component")
        seen.add(m.component)
        if 2 * world.horizon / (m.mttf + m.mttr) > MAX_RANDOM_CHANGES:  # a failure and a repair per cycle
            raise ScenarioError(
                f"world: MTTF of {m.component!r} (mttf {m.mttf:g} s, mttr {m.mttr:g} s) gives about "
                f"{2 * world.horizon / (m.mttf + m.mttr):,.0f} failures and repairs over the horizon of {world.horizon:g} s, "
                f"more than the {MAX_RANDOM_CHANGES:,} a run simulates; give a shorter horizon, or mttf + mttr of at least {2 * world.horizon / MAX_RANDOM_CHANGES:.3g} s"
            )
    object.__setattr__(world, "stochastic_faults", mttfs)
    walks = check_items("world: load_walks", world.load_walks, LoadWalk, error=err, example="(LoadWalk('arm_pc', start=300, sigma=15, interval=30),)")
    walked: set[tuple[str, str]] = set()
    for w in walks:
        if (w.platform, w.resource) in walked:
            raise ScenarioError(f"world: two load walks of {w.platform!r} {w.resource}: give one per platform and resource")
        walked.add((w.platform, w.resource))
        if world.horizon / w.interval > MAX_RANDOM_CHANGES:
            raise ScenarioError(
                f"world: load walk of {w.platform!r} every {w.interval:g} s over the horizon of {world.horizon:g} s is more "
                f"than the {MAX_RANDOM_CHANGES:,} steps a run simulates; give a shorter horizon, or an interval of at least {world.horizon / MAX_RANDOM_CHANGES:.3g} s"
            )
    object.__setattr__(world, "load_walks", walks)
    steps = check_items("world: load_steps", world.load_steps, LoadSteps, error=err, example="(LoadSteps('torso_pc', levels=(600, 800), start=600, mean_interval=300),)")
    for w in steps:
        if (w.platform, w.resource) in walked:
            raise ScenarioError(f"world: two load walks or load steps of {w.platform!r} {w.resource}: give one per platform and resource")
        walked.add((w.platform, w.resource))
        if world.horizon / w.mean_interval > MAX_RANDOM_CHANGES:
            raise ScenarioError(
                f"world: load steps of {w.platform!r} every {w.mean_interval:g} s on average over the horizon of {world.horizon:g} s "
                f"are more than the {MAX_RANDOM_CHANGES:,} steps a run simulates; give mean_interval at least {world.horizon / MAX_RANDOM_CHANGES:.3g}"
            )
    object.__setattr__(world, "load_steps", steps)
    _check_load_masters(world)
    _check_fault_masters(world)


def _check_fault_masters(world: World) -> None:
    """A component's failures have one master: scripted faults, or an MTTF, not both (the
    MTTF's next failure or repair would cut a scripted outage short, or the scripted
    failure fall on a component already failed)."""
    governed = {m.component for m in world.stochastic_faults}
    for te in world.faults:
        ev = te.event
        component = getattr(ev, "device", None) or getattr(ev, "platform", None)
        if component in governed:
            raise ScenarioError(
                f"world: {component!r} has two masters of its failures: an MTTF and the scripted '{ev}' at t={te.time:g} in "
                "faults=: let the MTTF drive it, or script it, not both"
            )


def _check_rates(given: object) -> tuple[tuple[str, float], ...]:
    """``World.detection_rates``: (graph, probability) pairs, each probability in (0, 1]."""
    rates = check_pairs("world: detection_rates", given, error=ScenarioError, example="{'camera_slip_detector': 0.8}")
    for g, v in rates:
        check_number(f"world: detection_rates of {g}", v, error=ScenarioError, high=1.0)
        if v <= 0:  # type: ignore[operator]
            raise ScenarioError(
                f"world: detection_rates gives {g!r} a rate of {v!r}: give a probability above 0 (a graph without a "
                "rate cannot detect: leave it out)"
            )
    return tuple((str(g), float(v)) for g, v in rates)  # type: ignore[arg-type]


def _check_rates_against(world: World, model: SystemModel, where: str) -> None:
    """A given rate names a graph of the model that has no signal model."""
    graphs = [g.name for g in model.graphs]
    blind = world.no_signal_model(model.graphs)
    for g, _v in world.detection_rates:
        if g not in graphs:
            raise ScenarioError(
                f"{where}: detection_rates names {g!r}{suggest(g, graphs)}, which is no perception graph of the model: "
                f"give the rate of one without a signal model ({', '.join(blind) or 'the model has none'})"
            )
        if g not in blind:
            raise ScenarioError(
                f"{where}: detection_rates gives {g!r} a rate, but every input it reads has a signal model, so its "
                "rate is measured from its signals: drop it from detection_rates"
            )


def _check_runtime_changes(world: World, model: SystemModel, where: str, changes: list[Event]) -> None:
    """Random requirement changes and the lease name what the model has."""
    for ev in world.random_changes.changes if world.random_changes else ():
        problem = event_problem(ev, model, changes)
        if problem is not None:
            raise ScenarioError(f"{where}: random changes: {problem}")
    if world.lease is None:
        return
    on_demand = [p.name for p in model.platforms if p.on_demand]
    if not on_demand:
        raise ScenarioError(f"{where}: lease given but no platform is on demand: declare one with on_demand=True or drop lease")
    for p in world.lease.platforms:
        if p not in on_demand:
            raise ScenarioError(f"{where}: lease names {p!r}, which is no on-demand platform{suggest(p, on_demand)} (on demand: {', '.join(on_demand)})")

#: the most task steps a run plays: a horizon that needs more (years of a task of seconds) is
#: refused in one line instead of filling the memory with them before the run starts
MAX_TASK_STEPS = 10_000_000


def expand_task(world: World, horizon: float, seed: int = 0) -> tuple[Segment, ...]:
    """The ground-truth segments up to ``horizon`` (the task once, or repeated); each
    segment's ``context`` is the step's action. Under exponential timing the task
    repeats and each step lasts an Erlang-``phases`` time of mean its duration, drawn
    from ``seed``. More than :data:`MAX_TASK_STEPS` of them are refused (a ScenarioError)."""
    if world.repeats:
        cycle = sum(step.duration for step in world.task)
        steps = horizon / cycle * len(world.task) if cycle > 0 else math.inf
        if steps > MAX_TASK_STEPS:
            raise ScenarioError(
                f"world: a run of {horizon:,.6g} s would play about {steps:,.3g} steps of its task ({cycle:g} s a cycle), more than "
                f"the {MAX_TASK_STEPS:,} a run holds: simulate a shorter horizon (--until S; desmon analyze: --horizon S; or the scenario's own length)"
            )
    if world.timing == "exponential":
        rng = random.Random(f"{seed}:task")
        k = world.phases

        def duration(step: Step) -> float:
            return sum(rng.expovariate(k / step.duration) for _ in range(k))
    else:
        def duration(step: Step) -> float:
            return step.duration
    out: list[Segment] = []
    t = 0.0
    while t < horizon:
        for step in world.task:
            if t >= horizon:
                break
            d = duration(step)
            out.append(Segment(step.action, float(t), float(d)))
            t += d
        if not world.repeats:
            break
    return tuple(out)


def _builtin(action: str) -> str:
    return action


def like_segments(segments: Sequence[Segment], like: Callable[[str], str]) -> tuple[Segment, ...]:
    """``segments`` with each context replaced by the built-in action it is like
    (``SystemModel.like``): what the signal models render, :func:`in_hand` and
    :func:`draw_slips` read. A model's own action has the signals of its ``like``."""
    out = []
    for s in segments:
        b = like(s.context)
        out.append(s if b == s.context else Segment(b, s.start, s.duration))
    return tuple(out)


def in_hand(segments: Sequence[Segment]) -> list[tuple[float, float, str]]:
    """Segments during which an object is in the hand (as MissionSignals renders episodes);
    built-in contexts only (map a model's own actions with :func:`like_segments`)."""
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


def slip_kind(world: World, action: str) -> tuple[str, str]:
    """(direction, kind) of a random slip in built-in ``action`` (:attr:`World.slip_kinds`)."""
    for a, d, k in world.slip_kinds:
        if a == action:
            return d, k
    return "down", "pulled"


def draw_slips(world: World, segments: Sequence[Segment], seed: int) -> tuple[Slip, ...]:
    """Scripted slips plus random ones, from their own seeded stream (``segments`` with
    built-in contexts: :func:`like_segments`).

    The one rule for random slips, which ``desmon analyze`` models exactly: a Poisson
    process of ``slip_rate`` per second over every moment with an object in the hand
    (:func:`in_hand`), whatever happened before; a slip's direction and kind are those
    :attr:`World.slip_kinds` gives for the action it falls in."""
    slips = list(world.slips)
    if world.slip_rate > 0:
        held = in_hand(segments)
        seconds = sum(end - start for start, end, _a in held)
        if world.slip_rate * seconds > MAX_RANDOM_CHANGES:
            raise ScenarioError(
                f"world: slip_rate {world.slip_rate:g} slips per second of object-in-hand time over {seconds:,.6g} s with an "
                f"object in the hand gives about {world.slip_rate * seconds:,.0f} slips, more than the {MAX_RANDOM_CHANGES:,} a run "
                "simulates: the rate is per second (one slip every 900 s is 1/900), or simulate a shorter horizon"
            )
        rng = random.Random(f"{seed}:slips")
        for start, end, action in held:
            direction, kind = slip_kind(world, action)
            t = start + rng.expovariate(world.slip_rate)
            while t < end:
                at = round(t, 4)
                if at < end:  # rounding never carries a slip past its step
                    slips.append(Slip(at, direction, kind))
                t += rng.expovariate(world.slip_rate)
    return tuple(sorted(slips, key=lambda s: s.time))


def detector_plans(world: World, model: SystemModel) -> dict[str, DetectorPlan | None]:
    """Graph -> the detector it runs (:func:`desmon.sim.streams.detector_plan`: its kind
    and warm-up), or None when an input has no signal model in ``world``: such a graph
    cannot detect a slip, so it never counts as watching (signals on or off), unless
    ``World.detection_rates`` gives its rate (:func:`can_detect`). Every engine takes
    warm-ups and the ability to detect from here."""
    return {
        g.name: detector_plan(frozenset(world.signal_of(k) or f"?{k}" for k in g.device_kinds)) if g.device_kinds else None
        for g in model.graphs
    }


def can_detect(world: World, plans: dict[str, DetectorPlan | None]) -> dict[str, bool]:
    """Graph -> whether it can detect a slip: it has a detector plan, or a given rate."""
    return {g: plan is not None or world.given_rate(g) is not None for g, plan in plans.items()}


def world_from_timeline(scenario: Scenario) -> World:
    """A world that plays a scenario's scripted ``timeline``: action changes become task
    steps (idle until the first; a scenario's ``initial`` holds no action), device / platform events scripted
    faults, load changes scripted loads, requirement changes and joins run-time changes;
    the two changes of a :class:`~desmon.model.events.Together` both at its time (the
    world's deployer answers them in one reaction)."""
    timeline = tuple(
        TimedEvent(te.time, part, te.label) for te in scenario.timeline
        for part in ((te.event.first, te.event.second) if isinstance(te.event, Together) else (te.event,))
    )
    actions = [(te.time, te.event.action) for te in timeline if te.event.role == "action"]
    last = scenario.timeline[-1].time if scenario.timeline else 0.0
    horizon = last + 5.0
    if not actions or actions[0][0] > 0:
        actions.insert(0, (0.0, IDLE))
    steps = []
    for i, (t, a) in enumerate(actions):
        end = actions[i + 1][0] if i + 1 < len(actions) else horizon
        if end > t:
            steps.append(Step(a, end - t))
    faults = tuple(te for te in timeline if te.event.role == "fault")
    loads = tuple(te for te in timeline if te.event.role == "load")
    changes = tuple(te for te in timeline if te.event.role == "change")
    return World(task=tuple(steps), horizon=horizon, faults=faults, loads=loads, changes=changes, signals=False)


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
