"""Sensors and detectors of the SimPy world, in blocks.

The robot's two signal streams (wrench 50 Hz, six tactile pads ~30 Hz with jitter) come
from one :class:`desmon.detectors.signals.MissionSignals` for the whole mission, so a
sample depends only on the seed and its index. A device samples its stream at its own
rate; a failed device produces no samples (a failed tactile pad reads zero while other
pads still work; with every pad failed there are no frames). Signal generation is
pulled: a stream nobody consumes is never rendered. The segments it renders have
built-in contexts only: the SimPy world maps a model's own actions to the built-in they
are declared like (``desmon.sim.world.like_segments``).

:class:`DetectorAdapter` gives the SimPy world one interface over the streaming
detectors of :mod:`desmon.detectors` (force, tactile, combined): which detector a graph
runs, its warm-up and the samples it consumes follow from the stream classes of
:mod:`desmon.sim.streams` (:func:`~desmon.sim.streams.detector_plan`).
"""

from __future__ import annotations

import math
from typing import Any, Mapping, Sequence

import numpy as np

from desmon.detectors.base import Alarm
from desmon.detectors.signals import N_PADS, MissionSignals, Segment, SlipEvent
from desmon.detectors.tactile import FlowHint
from desmon.model.platform import Device
from desmon.sim.streams import detector_plan, fusions, signal_streams
from desmon.sim.world import Slip

__all__ = ["SensorBank", "DetectorAdapter", "WARMUP"]

#: Seconds of warm-up after activation by detector kind (force re-tare 0.5 s, tactile 3
#: frames, combined the longer), derived from the stream classes as of import.
WARMUP = {
    plan.kind: plan.warmup
    for plan in (detector_plan(frozenset(s)) for s in [*((st.name,) for st in signal_streams()), *(f.streams for f in fusions())])
    if plan is not None
}


class SensorBank:
    """Every device's sampling, over one deterministic mission signal source."""

    def __init__(self, segments: Sequence[Segment], slips: Sequence[Slip], seed: int, devices: Sequence[tuple[Device, str]]) -> None:
        self.signals = MissionSignals(
            segments,
            [SlipEvent(s.time, s.direction, s.kind) for s in slips],
            seed=seed,
        )
        #: device name -> signal stream
        self.stream = {d.name: s for d, s in devices}
        #: device name -> pad index for single tactile pads (kind tactile_pad)
        pads = [d.name for d, s in devices if s == "tactile" and d.kind == "tactile_pad"]
        self.pad = {name: i % N_PADS for i, name in enumerate(pads)}
        #: device name -> list of [fail_start, fail_end) intervals
        self.down: dict[str, list[list[float]]] = {d.name: [] for d, _ in devices}
        #: samples rendered per stream
        self.samples = {s.name: 0 for s in signal_streams()}
        #: the pads a graph reading these tactile pads reaches, by the pads' names (read only)
        self._covered: dict[tuple[str, ...], np.ndarray] = {}

    def fail(self, device: str, t: float) -> None:
        iv = self.down.get(device)
        if iv is not None and (not iv or iv[-1][1] < math.inf):
            iv.append([t, math.inf])

    def repair(self, device: str, t: float) -> None:
        iv = self.down.get(device)
        if iv and iv[-1][1] == math.inf:
            iv[-1][1] = t

    def working(self, device: str, t: float) -> bool:
        iv = self.down.get(device)
        return not iv or not (iv[-1][0] <= t < iv[-1][1])

    def _up_mask(self, device: str, times: np.ndarray) -> np.ndarray | None:
        iv = self.down.get(device)
        if not iv:
            return None
        lo = float(times[0]) if times.size else 0.0
        if iv[-1][1] <= lo:  # up again since before the first sample (times ascend)
            return None
        ok = np.ones(times.shape, dtype=bool)
        for a, b in reversed(iv):
            if b <= lo:
                break
            ok &= ~((times >= a) & (times < b))
        return ok

    def wrench(self, t0: float, t1: float, devices: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
        """Wrench samples in ``[t0, t1)`` from any working one of ``devices``."""
        if t1 <= t0 or not devices:
            return np.zeros(0), np.zeros(0)
        blk = self.signals.wrench(t0, t1)
        keep = None
        for d in devices:
            m = self._up_mask(d, blk.times)
            if m is None:
                keep = None
                break
            keep = m if keep is None else (keep | m)
        self.samples["wrench"] += int(blk.times.size)
        if keep is None:
            return blk.times, blk.values
        return blk.times[keep], blk.values[keep]

    def tactile(self, t0: float, t1: float, devices: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
        """Tactile frames (moments ``(K, 6, 3)``) in ``[t0, t1)``; failed pads read zero."""
        t, mom, _flow = self.tactile_read(t0, t1, devices)
        return t, mom

    def _pads_read(self, mom: np.ndarray, pads: Sequence[str], down: Sequence[tuple[str, np.ndarray]]) -> np.ndarray:
        """Moments ``mom`` as a graph reading the tactile ``pads`` alone sees them: a down pad's
        frames and the pads it cannot reach read zero (a changed copy), else ``mom`` itself."""
        key = tuple(pads)
        covered = self._covered.get(key)
        if covered is None:
            covered = self._covered[key] = np.zeros(N_PADS, dtype=bool)
            for d in pads:
                covered[self.pad[d]] = True
            covered.setflags(write=False)
        if down:
            mom = mom.copy()
            for d, m in down:
                mom[~m, self.pad[d], :] = 0.0
        if not covered.all():  # pads the graph cannot reach read nothing
            mom = mom.copy()
            mom[:, ~covered, :] = 0.0
        return mom

    def tactile_read(self, t0: float, t1: float, devices: Sequence[str]) -> tuple[np.ndarray, np.ndarray, FlowHint | None]:
        """:meth:`tactile`, and the frames' flow worked out ahead (:class:`FlowHint`) if a worker
        rendering ahead gave it and the frames are the stream's own, every one, unchanged."""
        if t1 <= t0 or not devices:
            return np.zeros(0), np.zeros((0, N_PADS, 3)), None
        blk = self.signals.tactile(t0, t1)
        t, mom = blk.times, blk.moments
        flow = None if blk.flow is None or not t.size else FlowHint(int(blk.index[0]), blk.flow)
        self.samples["tactile"] += int(t.size)
        pads = [d for d in devices if d in self.pad]
        # the devices down at some frame, with their masks (None: up at every frame)
        masks = [(d, self._up_mask(d, t)) for d in devices]
        down = [(d, m) for d, m in masks if m is not None and not m.all()]
        if len(pads) == len(devices):
            read = self._pads_read(mom, pads, down)
            if read is not mom:  # the frames changed: their flow is not the stream's
                mom, flow = read, None
        if len(down) < len(masks):  # some device is up at every frame
            return t, mom, flow
        any_ok = np.zeros(t.shape, dtype=bool)
        for _, m in down:
            any_ok |= m
        if any_ok.all():
            return t, mom, flow
        return t[any_ok], mom[any_ok], None


class DetectorAdapter:
    """One streaming detector of :mod:`desmon.detectors` behind a uniform ``feed``; which
    one follows from the streams it reads (:func:`desmon.sim.streams.detector_plan`)."""

    def __init__(self, streams: frozenset[str], name: str) -> None:
        self.streams = streams
        self.name = name
        plan = detector_plan(streams)
        self.kind = plan.kind if plan is not None else "none"
        self.det = plan.factory(name) if plan is not None else None
        self._plan = plan

    @property
    def warmup(self) -> float:
        return self._plan.warmup if self._plan is not None else 0.0

    def activate(self, t: float) -> None:
        if self.det is not None:
            self.det.activate(t)

    def deactivate(self) -> None:
        if self.det is not None:
            self.det.deactivate()

    def feed(self, bank: SensorBank, t0: float, t1: float, devices: Mapping[str, Sequence[str]]) -> tuple[Alarm, ...]:
        """Consume every sample in ``[t0, t1)`` of ``devices`` (stream -> devices read); return the alarms."""
        det = self.det
        if det is None or t1 <= t0 or self._plan is None:
            return ()
        args: list[Any] = []
        hints: dict[str, Any] = {}
        for stream in self._plan.streams:
            samples, offered = stream.read(bank, t0, t1, devices.get(stream.name, ()))
            args.extend(samples)
            hints.update(offered)
        taken = getattr(det, "hints", ())
        return det.process(*args, until=t1, **{k: v for k, v in hints.items() if k in taken and v is not None})  # type: ignore[no-any-return]
