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
detectors of :mod:`desmon.detectors` (force, tactile, combined).
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from desmon.detectors.base import Alarm
from desmon.detectors.signals import N_PADS, MissionSignals, Segment, SlipEvent
from desmon.model.platform import Device
from desmon.sim.world import Slip

__all__ = ["SensorBank", "DetectorAdapter", "WARMUP"]

#: Seconds of warm-up after activation: force re-tare 0.5 s, tactile 3 frames.
WARMUP = {"wrench": 0.5, "tactile": 3.0 / 30.0, "both": 0.5}


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
        self.samples = {"wrench": 0, "tactile": 0}

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
        ok = np.ones(times.shape, dtype=bool)
        lo = float(times[0]) if times.size else 0.0
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
        if t1 <= t0 or not devices:
            return np.zeros(0), np.zeros((0, N_PADS, 3))
        blk = self.signals.tactile(t0, t1)
        t, mom = blk.times, blk.moments
        self.samples["tactile"] += int(t.size)
        pads = [d for d in devices if d in self.pad]
        arrays = [d for d in devices if d not in self.pad]
        any_ok = np.zeros(t.shape, dtype=bool)
        masks = []
        for d in devices:
            m = self._up_mask(d, t)
            m = np.ones(t.shape, dtype=bool) if m is None else m
            masks.append((d, m))
            any_ok |= m
        if pads and not arrays:
            covered = np.zeros(N_PADS, dtype=bool)
            changed = False
            for d, m in masks:
                covered[self.pad[d]] = True
                if not m.all():
                    if not changed:
                        mom = mom.copy()
                        changed = True
                    mom[~m, self.pad[d], :] = 0.0
            if not covered.all():  # pads the graph cannot reach read nothing
                mom = mom.copy()
                mom[:, ~covered, :] = 0.0
        if any_ok.all():
            return t, mom
        return t[any_ok], mom[any_ok]


class DetectorAdapter:
    """One streaming detector of :mod:`desmon.detectors` behind a uniform ``feed``."""

    def __init__(self, streams: frozenset[str], name: str) -> None:
        self.streams = streams
        self.name = name
        if streams == frozenset({"wrench"}):
            from desmon.detectors.force import ForceDetector

            self.kind = "wrench"
            self.det = ForceDetector(name=name)
        elif streams == frozenset({"tactile"}):
            from desmon.detectors.tactile import TactileDetector

            self.kind = "tactile"
            self.det = TactileDetector(name=name)
        elif streams == frozenset({"wrench", "tactile"}):
            from desmon.detectors.combined import CombinedDetector

            self.kind = "both"
            self.det = CombinedDetector(name=name)
        else:
            self.kind = "none"
            self.det = None

    @property
    def warmup(self) -> float:
        return WARMUP.get(self.kind, 0.0)

    def activate(self, t: float) -> None:
        if self.det is not None:
            self.det.activate(t)

    def deactivate(self) -> None:
        if self.det is not None:
            self.det.deactivate()

    def feed(self, bank: SensorBank, t0: float, t1: float, wrench_devs: Sequence[str], tactile_devs: Sequence[str]) -> tuple[Alarm, ...]:
        """Consume every sample in ``[t0, t1)`` of the given devices; return the alarms."""
        det = self.det
        if det is None or t1 <= t0:
            return ()
        if self.kind == "wrench":
            wt, wv = bank.wrench(t0, t1, wrench_devs)
            return det.process(wt, wv, until=t1)
        if self.kind == "tactile":
            tt, tm = bank.tactile(t0, t1, tactile_devs)
            return det.process(tt, tm, until=t1)
        wt, wv = bank.wrench(t0, t1, wrench_devs)
        tt, tm = bank.tactile(t0, t1, tactile_devs)
        return det.process(wt, wv, tt, tm, until=t1)
