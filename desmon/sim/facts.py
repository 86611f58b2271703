"""The physical facts of one robot's SimPy world, and its ground truth.

:class:`PhysicalFacts` is what is *really* so, whatever the repository says: which
platforms are up, their background memory load, which devices work, which detector
instances run where and what each consumes. The Control infrastructure
(:mod:`desmon.sim.infrastructure`) changes it; the exposure meter, the audit and the
Control rules read it.

:class:`GroundTruth` is what the robot does and what happens to it: the task's
segments, the slips drawn for the run, the sensor bank (signals on) and the detector
wake-up grid around the slips (:meth:`GroundTruth.next_wake`).
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass, field
from typing import Any, Mapping

from desmon.deployment.exposure import best_state
from desmon.detectors.signals import Segment
from desmon.errors import ScenarioError
from desmon.model.system import PlatformState, SystemModel
from desmon.sim.sensors import DetectorAdapter, SensorBank
from desmon.sim.world import Slip, World, draw_slips, expand_task, like_segments

__all__ = ["Instance", "PhysicalFacts", "GroundTruth", "SLIP_WINDOW"]

#: Around a ground-truth slip at t_s, detectors wake every ``world.block`` seconds in
#: [t_s + lo, t_s + hi] (a pulled slip loads the wrist up to 1 s before motion onset;
#: the detection window ends 1 s after it).
SLIP_WINDOW = (-2.0, 2.0)


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
    ready_at: float = 0.0  # exponential timing: when its start latency has passed (never valid before)
    #: the spans ``(t0, t1)`` of this activation not yet run through its detector, far from every slip
    #: (a run that reads no alarm outside the slips' windows: Infrastructure.feed)
    deferred: list[tuple[float, float]] = field(default_factory=list)


class _Readability(dict):  # type: ignore[type-arg]
    """A dict of what decides whether a device can be read (platforms up, devices
    working): every item assignment moves the owner's ``readability`` version, on which
    :meth:`PhysicalFacts.inputs_ok` memoises its answers."""

    def __init__(self, owner: "PhysicalFacts", items: dict[str, bool]) -> None:
        super().__init__(items)
        self.owner = owner

    def __setitem__(self, key: str, value: bool) -> None:
        super().__setitem__(key, value)
        self.owner.readability += 1

    # every other way to change a dict moves the version too: a memo that missed a
    # write would answer that a dead sensor can be read
    def __delitem__(self, key: str) -> None:
        super().__delitem__(key)
        self.owner.readability += 1

    def update(self, *args: Any, **kw: Any) -> None:
        super().update(*args, **kw)
        self.owner.readability += 1

    def pop(self, *args: Any) -> Any:
        self.owner.readability += 1
        return super().pop(*args)

    def popitem(self) -> tuple[str, bool]:
        self.owner.readability += 1
        return super().popitem()

    def setdefault(self, key: str, default: Any = None) -> Any:
        self.owner.readability += 1
        return super().setdefault(key, default)

    def clear(self) -> None:
        super().clear()
        self.owner.readability += 1

    def __ior__(self, other: Any) -> "_Readability":
        self.update(other)
        return self


class PhysicalFacts:
    """Platforms up (an on-demand one absent until it joins), loads, devices, instances."""

    def __init__(self, model: SystemModel) -> None:
        self.model = model
        #: moves with every write to ``up`` or ``dev_ok`` (what makes a device readable)
        self.readability = 0
        self.up: dict[str, bool] = _Readability(self, {p.name: not p.on_demand for p in model.platforms})
        self.load: dict[str, float] = {p.name: 0.0 for p in model.platforms}
        self.dev_ok: dict[str, bool] = _Readability(self, {d.name: True for d in model.devices})
        self.host = {d.name: d.platform for d in model.devices}
        self.hosted = {p.name: model.devices_on(p.name) for p in model.platforms}
        self.instances: dict[tuple[str, str], Instance] = {}
        #: (graph, platform) started and waiting out its start latency (fixed timing) -> the
        #: devices it will read (stream -> device names, as an instance's ``streams``)
        self.pending: dict[tuple[str, str], Mapping[str, tuple[str, ...]]] = {}
        #: graph -> whether it can detect a slip (its inputs have a signal model); set by
        #: the world's assembly (:func:`desmon.sim.world.detector_plans`)
        self.detects: dict[str, bool] = {}
        self._states: dict[str, tuple[int, PlatformState]] = {}  # platform -> (readability, state)
        # id of an instance's streams -> (those streams, readability, whether all are readable)
        self._inputs: dict[int, tuple[dict[str, tuple[str, ...]], int, bool]] = {}
        #: memory (MB) a running instance of each graph consumes: its spec's consumption()
        self.consumes = {s.graph: dict(s.consumption()).get("memory", 0.0) for s in model.specs}

    def used(self, p: str) -> float:
        """Memory in use on ``p``: its background load and its instances (0 while down)."""
        if not self.up[p]:
            return 0.0
        return self.load[p] + sum(i.memory for i in self.instances.values() if i.platform == p)

    def readable(self, device: str) -> bool:
        """A device's signal reaches a detector while it works and its platform is up."""
        return self.dev_ok[device] and self.up[self.host[device]]

    def inputs_ok(self, inst: Instance) -> bool:
        """Every stream of ``inst`` has a readable device (memoised per streams object --
        the infrastructure hands out one per graph and platform -- while no platform goes
        up or down and no device fails or is repaired)."""
        streams = inst.streams
        version = self.readability
        seen = self._inputs.get(id(streams))
        if seen is not None and seen[0] is streams and seen[1] == version:
            return seen[2]
        ok = all(any(self.readable(d) for d in devs) for devs in streams.values())
        if len(self._inputs) > 1024:
            self._inputs.clear()
        self._inputs[id(streams)] = (streams, version, ok)  # the entry holds the object its key names
        return ok

    def state(self, platform: str) -> PlatformState:
        """The physical facts of ``platform`` the Control rules read (up, working devices);
        the same object while no platform goes up or down and no device fails or is repaired."""
        version = self.readability
        hit = self._states.get(platform)
        if hit is not None and hit[0] == version:
            return hit[1]
        state = PlatformState(
            self.model.platform(platform),
            self.up[platform],
            tuple(d for d in self.hosted[platform] if self.dev_ok[d.name]),
        )
        self._states[platform] = (version, state)
        return state

    def alive(self, inst: Instance) -> bool:
        return self.up[inst.platform] and not inst.halted and self.inputs_ok(inst)

    def valid_from(self, graph: str) -> float:
        """The earliest time a running instance of ``graph`` is valid from (inf: none)."""
        return self.valid_times().get(graph, math.inf)

    def valid_times(self) -> dict[str, float]:
        """:meth:`valid_from` of every graph with a live instance, in one pass (a graph
        not in it: inf)."""
        out: dict[str, float] = {}
        up = self.up
        inputs_ok = self.inputs_ok
        for inst in self.instances.values():
            if up[inst.platform] and not inst.halted and inputs_ok(inst):  # alive(inst), inline
                g = inst.graph
                t = out.get(g)
                out[g] = inst.valid_from if t is None else min(t, inst.valid_from)
        return out

    def member_state(self, graph: str, now: float) -> str:
        """The state of ``graph`` as a slot member at ``now`` (the best over its instances
        and pending starts): one of :data:`desmon.deployment.exposure.MEMBER_STATES`."""
        states = []
        for (g, platform), streams in self.pending.items():  # asked as an instance is: alive, able to detect, then starting
            if g != graph:
                continue
            if not (self.up[platform] and all(any(self.readable(d) for d in devs) for devs in streams.values())):
                states.append("input_lost")
            else:
                states.append("starting" if self.detects.get(graph, True) else "cannot_detect")
        for inst in self.instances.values():
            if inst.graph != graph:
                continue
            if not (self.up[inst.platform] and not inst.halted and self.inputs_ok(inst)):
                states.append("input_lost")
            elif not self.detects.get(graph, True):
                states.append("cannot_detect")
            elif inst.valid_from > now:
                states.append("starting")
            else:
                states.append("watching")
        return best_state(states)

    def physically_valid(self, graph: str, platform: str) -> bool:
        """Whether the running instance of ``graph`` on ``platform`` can monitor: its
        platform is up and every stream it reads has a readable device (warm-up aside)."""
        inst = self.instances.get((graph, platform))
        return inst is not None and self.up[platform] and self.inputs_ok(inst)


class GroundTruth:
    """Task segments, slips and (with signals on) the sensor bank of one run."""

    def __init__(self, world: World, model: SystemModel, horizon: float, seed: int, signals: bool) -> None:
        self.world = world
        self.segments: tuple[Segment, ...] = expand_task(world, horizon, seed)
        #: the same segments as the signals see them: each action replaced by the built-in it is like
        physical = like_segments(self.segments, model.like)
        slips = draw_slips(world, physical, seed)
        self.slips: tuple[Slip, ...] = tuple(s for s in slips if s.time < horizon)
        self._busy = _merge_windows([(s.time + SLIP_WINDOW[0], s.time + SLIP_WINDOW[1]) for s in self.slips])
        devs = [(d, world.signal_of(d.kind)) for d in model.devices]
        self.stream_of = {d.name: s for d, s in devs}
        self.bank: SensorBank | None = None
        if signals:
            whole, whole_slips = _whole_run(world, model, horizon, seed, physical, self.slips)
            self.bank = SensorBank(whole, whole_slips, seed, [(d, s) for d, s in devs if s is not None])

    def near_slip(self, t0: float, t1: float) -> bool:
        """Whether ``[t0, t1]`` meets a slip's window (:data:`SLIP_WINDOW` around its onset:
        wider than the window in which an alarm detects it)."""
        lo, hi = self._busy
        i = bisect.bisect_left(hi, t0)
        return i < len(lo) and lo[i] <= t1

    def next_wake(self, now: float) -> float:
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


def _whole_run(world: World, model: SystemModel, horizon: float, seed: int, physical: tuple[Segment, ...],
               slips: tuple[Slip, ...]) -> tuple[tuple[Segment, ...], tuple[Slip, ...]]:
    """The segments (as the signals see them) and slips of the whole run the World describes,
    for the signals of a run cut short before its horizon (``--until``): the signals draw each
    step's and each slip's parameters in turn from one stream, so only signals drawn for the
    whole run make a shorter run's first seconds those of the whole one. A World too long to
    expand whole keeps the short run's own (``physical``, ``slips``)."""
    if horizon >= world.horizon:
        return physical, slips
    try:
        whole = like_segments(expand_task(world, world.horizon, seed), model.like)
        return whole, tuple(s for s in draw_slips(world, whole, seed) if s.time < world.horizon)
    except ScenarioError:  # (more steps or slips than a run holds: the cut run's are all there is)
        return physical, slips


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
