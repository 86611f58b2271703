"""Mission assembly: one mission's wrench and tactile streams, built from their parts.

:class:`MissionSignals` checks its inputs, draws the episodes' and slips' parameters from
the mission's parameter generator (in that order: the seed contract), and hands each sensor
its share: :class:`~desmon.detectors.signals.wrench.WrenchSensor` gets the segments and
slips, :class:`~desmon.detectors.signals.tactile_array.TactileArray` the episodes with their
slips. Sampling is delegated to them.
"""

from __future__ import annotations

from typing import Callable, Sequence

import numpy as np

from desmon.detectors.signals.common import (
    DEFAULT_PARAMS,
    Arr,
    Segment,
    SensorFault,
    SignalParams,
    SlipEvent,
    SlipTruth,
    TactileBlock,
    WrenchBlock,
    WrenchSource,
    check_contexts,
    check_faults,
)
from desmon.detectors.signals.episodes import plan_episodes
from desmon.detectors.signals.noise import STREAM_PARAMS, block_rng
from desmon.detectors.signals.slips import draw_slips, slip_events, with_slips
from desmon.detectors.signals.tactile_array import TactileArray
from desmon.detectors.signals.wrench import WrenchSensor, wrench_config
from desmon.errors import SignalError


def _check_seed(seed: object) -> int:
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0:
        raise SignalError(f"seed {seed!r} must be a non-negative integer")
    return int(seed)


def _segments(segments: Sequence[Segment | tuple[str, float, float]]) -> tuple[Segment, ...]:
    segs = tuple(s if isinstance(s, Segment) else Segment(str(s[0]), float(s[1]), float(s[2])) for s in segments)
    check_contexts(segs)
    return segs


class MissionSignals:
    """Deterministic wrench and tactile streams for a whole mission (the SimPy world's sensor source).

    Parameters
    ----------
    segments:
        ``Segment`` objects or ``(context, start_s, duration_s)`` tuples, in time order,
        contexts from :mod:`desmon.model.actions`. Gaps between segments count as idle
        (nothing in hand). A grasp starts an object-in-hand episode, the end of a release
        (or idle) ends it; a mission that starts with another risky context starts with
        the object already in the hand.
    slips:
        ``SlipEvent`` objects or ``(onset_s, direction, kind)`` tuples. ``onset`` is slip
        *motion* onset; a pulled slip loads the wrist up to 1 s earlier. A slip must fall
        inside an episode (object in hand).
    seed:
        Every random quantity derives from it: per-segment and per-slip parameters are
        drawn up front at construction; per-sample noise and tactile jitter come from
        generators keyed by ``(seed, stream, block number)``, so a sample depends only on
        its index, never on how requests are chunked.
    wrench_source / wrench_rate:
        ``"lwr_estimate"`` (default, 50 Hz, sigma 0.3 N, base inertia leaks into the
        estimate) or ``"wrist_ft"`` (100–1000 Hz, sigma 0.05 N, weak coupling).
    faults:
        ``SensorFault`` list (silent / stuck / zero from a time on).
    two_finger:
        Grasp type per episode; default alternates three-finger / two-finger.

    Sampling
    --------
    ``wrench(t0, t1)`` / ``tactile(t0, t1)`` return every sample whose time lies in
    ``[t0, t1)``; ``wrench_at(index)`` / ``tactile_at(index)`` return samples by grid
    index. Wrench sample ``k`` is at ``k / wrench_rate``; tactile frame ``k`` at
    ``k / 30 + jitter_k`` (jitter N(0, 2 ms) clipped to +-8 ms, so frames stay ordered).
    """

    def __init__(
        self,
        segments: Sequence[Segment | tuple[str, float, float]],
        slips: Sequence[SlipEvent | tuple[float, str, str]] = (),
        *,
        seed: int = 0,
        wrench_source: WrenchSource = "lwr_estimate",
        wrench_rate: float | None = None,
        faults: Sequence[SensorFault] = (),
        params: SignalParams = DEFAULT_PARAMS,
        two_finger: Sequence[bool] | None = None,
    ) -> None:
        self.seed = _check_seed(seed)
        self.segments = _segments(segments)
        self.slips = slip_events(slips)
        config = wrench_config(wrench_source, wrench_rate, params)
        self.faults = check_faults(faults)
        self.params = params
        self.wrench_source = wrench_source
        self.wrench_rate = config.rate
        self.tactile_rate = params.tactile_rate
        rng = block_rng(self.seed, STREAM_PARAMS, 0)
        episodes, seg_params = plan_episodes(self.segments, rng, params, two_finger)
        drawn = draw_slips(self.slips, episodes, rng, params)
        self.slip_truth: tuple[SlipTruth, ...] = tuple(s.truth for s in drawn)
        self.wrench_sensor = WrenchSensor(self.seed, config, self.segments, seg_params, drawn, self.faults, params)
        self.tactile_array = TactileArray(self.seed, with_slips(episodes, drawn), self.faults, params)

    def start_ahead(self, tactile_flow: Callable[[np.ndarray, np.ndarray | None], np.ndarray] | None = None, *, wrench: bool = False) -> None:
        """Render the tactile frames ahead in a forked worker, and with ``wrench`` the wrench in
        a second one (:mod:`desmon.detectors.signals.ahead`); the samples are the same bytes
        either way. With ``tactile_flow`` (``desmon.detectors.tactile.flow_ahead``) the tactile
        worker works out the frames' flow too (``TactileBlock.flow``). A stream whose worker
        cannot be forked (the system refuses a process) renders here.

        The wrench stays here unless asked: a request by time renders only its own samples
        of a block, so a run whose force graphs read a small part of the mission (the robot
        day reads 80k of its 1.44 M samples) renders far less here than a worker rendering
        every block would, and a second worker takes CPU from the first (docs/design.md,
        "Rendering ahead")."""
        if not isinstance(wrench, bool):
            raise SignalError(f"start_ahead: wrench {wrench!r} must be True or False")
        starts = [lambda: self.tactile_array.start_ahead(tactile_flow)]
        if wrench:
            starts.append(self.wrench_sensor.start_ahead)
        for start in starts:
            try:
                start()
            except OSError:
                pass

    def stop_ahead(self) -> None:
        """Stop the workers rendering ahead (if any); from then on every sample is rendered here."""
        self.tactile_array.stop_ahead()
        self.wrench_sensor.stop_ahead()

    @property
    def ahead_taken(self) -> int:
        """Blocks (tactile and wrench) taken from workers rendering ahead so far."""
        return self.tactile_array.ahead_taken + self.wrench_sensor.ahead_taken

    @property
    def end_time(self) -> float:
        """End of the last segment."""
        return float(self.segments[-1].end) if self.segments else 0.0

    def wrench_at(self, index: Arr) -> WrenchBlock:
        """Wrench samples for grid indices ``index`` (int array, >= 0), faults applied."""
        return self.wrench_sensor.at(index)

    def wrench(self, t0: float, t1: float) -> WrenchBlock:
        """All wrench samples with ``t0 <= t < t1``."""
        return self.wrench_sensor.between(t0, t1)

    def tactile_times(self, index: Arr) -> Arr:
        """Jittered time of each frame number."""
        return self.tactile_array.times(index)

    def tactile_at(self, index: Arr, frames: bool = False) -> TactileBlock:
        """Tactile frames by frame number (int array, >= 0), faults applied."""
        return self.tactile_array.at(index, frames)

    def tactile(self, t0: float, t1: float, frames: bool = False) -> TactileBlock:
        """All tactile frames with ``t0 <= t < t1`` (moments always; full frames if ``frames``)."""
        return self.tactile_array.between(t0, t1, frames)
