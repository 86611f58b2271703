"""The hand: object-in-hand episodes and the grasp contact that shapes the tactile pads.

A grasp starts an episode, the end of a release (an idle segment, or a gap in the
timeline) ends it; a mission that starts with another risky context starts with the
object already in the hand. :func:`plan_episodes` walks the timeline once and draws, in
timeline order from the one parameter generator, each episode's contact constants
(:func:`draw_contact`) followed by the parameters of each of its segments
(:func:`desmon.detectors.signals.contexts.draw_context`): that order is part of the seed
contract, since every later draw (the slips) continues the same generator.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from desmon.detectors.signals.common import DEFAULT_PARAMS, N_PADS, PAD_ROWS, Arr, Params, Segment, SignalParams
from desmon.detectors.signals.common import uniform as _u
from desmon.detectors.signals.contexts import draw_context
from desmon.model.actions import GRASP, IDLE, RELEASE


#: Each pad's rows minus 5: the span of its contact's row centre above 2.
_Y_SPAN = np.asarray(PAD_ROWS, dtype=float) - 5.0


@dataclass(frozen=True, slots=True)
class Episode:
    """An object-in-hand interval: contact constants, its action segments and slips."""

    start: float
    end: float
    contact: Params
    segments: tuple[tuple[str, float, float, Params], ...]
    slips: tuple[tuple[Arr, Arr, Params], ...]  # (t_s (n,), sign (n,), slip params)


def draw_contact(rng: np.random.Generator, n: int, two_finger: Arr, p: SignalParams = DEFAULT_PARAMS) -> Params:
    """Per-pad contact constants for ``n`` grasps (research note §3.2; [BAG]).

    Three-finger grasps touch 3-4 pads, two-finger grasps 2-3; pads not in contact
    get amplitude 0.
    """
    order = rng.random((n, N_PADS)).argsort(axis=1)
    rank = order.argsort(axis=1)
    m = np.where(two_finger, rng.integers(2, 4, n), rng.integers(3, 5, n))
    contact = rank < m[:, None]
    amp = np.exp(rng.uniform(math.log(p.peak_lo), math.log(p.peak_hi), (n, N_PADS)))
    return {
        "contact": contact,
        "A": np.where(contact, amp, 0.0),
        "sy": _u(rng, (p.sigma_lo, p.sigma_hi), (n, N_PADS)),
        "sx": _u(rng, (p.sigma_lo, p.sigma_hi), (n, N_PADS)),
        "y": 2.0 + rng.random((n, N_PADS)) * _Y_SPAN,  # U(2, R - 3)
        "x": _u(rng, (1.5, 3.5), (n, N_PADS)),
        "kappa": rng.uniform(0.0, p.creep_max, n),
    }


class _Planner:
    """The open episode while :func:`plan_episodes` walks the timeline."""

    def __init__(self, rng: np.random.Generator, params: SignalParams, two_finger: Sequence[bool] | None) -> None:
        self.rng = rng
        self.params = params
        self.two_finger = two_finger
        self.episodes: list[Episode] = []
        self.start: float | None = None
        self.contact: Params | None = None
        self.segs: list[tuple[str, float, float, Params]] = []
        self.count = 0

    def last_end(self) -> float:
        return self.segs[-1][1] + self.segs[-1][2]

    def close(self, end: float) -> None:
        if self.start is not None and self.contact is not None:
            self.episodes.append(Episode(self.start, end, self.contact, tuple(self.segs), ()))
        self.start, self.contact, self.segs = None, None, []

    def open(self, start: float) -> None:
        self.close(start)
        n_ep = self.count
        tf = (n_ep % 2 == 1) if self.two_finger is None else bool(self.two_finger[n_ep % len(self.two_finger)])
        self.contact = draw_contact(self.rng, 1, np.array([tf]), self.params)
        self.start = start
        self.count += 1

    def add(self, s: Segment) -> Params:
        """Segment ``s``'s parameters, opening or closing episodes around it."""
        if self.start is not None and self.segs and s.start > self.last_end() + 1e-9:
            self.close(self.last_end())  # a gap: the hand is empty
        if s.context == IDLE:
            self.close(s.start)
            return {}
        if s.context == GRASP or self.start is None:
            self.open(s.start)
        cp = draw_context(s.context, self.rng, 1, self.contact["contact"] if self.contact else None, self.params)
        self.segs.append((s.context, s.start, s.duration, cp))
        if s.context == RELEASE:
            self.close(s.end)
        return cp


def plan_episodes(
    segments: Sequence[Segment],
    rng: np.random.Generator,
    params: SignalParams = DEFAULT_PARAMS,
    two_finger: Sequence[bool] | None = None,
) -> tuple[tuple[Episode, ...], tuple[Params, ...]]:
    """The object-in-hand episodes of a (checked) timeline, without slips, and each segment's
    parameters (``{}`` for idle). Grasp types follow ``two_finger`` per episode (cycled),
    by default alternating three-finger / two-finger."""
    planner = _Planner(rng, params, two_finger)
    seg_params = tuple(planner.add(s) for s in segments)
    if planner.start is not None and planner.segs:
        planner.close(planner.last_end())
    return tuple(planner.episodes), seg_params
