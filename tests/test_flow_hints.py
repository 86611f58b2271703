"""Flow hints: the tactile worker rendering ahead works out the frames' tactile flow too, and
the tactile detector takes it where, and only where, it is the flow it would have worked out.

The rule a user relies on: a detector fed hinted frames gives the very ``S_T``, validity and
status, byte for byte, that it gives fed the same frames without hints, whatever the chunks,
gaps, activations and pad failures."""

from __future__ import annotations

import os

import numpy as np
import pytest
from conftest import deliveries, refused

from desmon.detectors.signals import MissionSignals, SlipEvent
from desmon.detectors.tactile import FlowHint, TactileDetector, flow_ahead
from desmon.errors import SignalError
from desmon.model.platform import Device
from desmon.sim.sensors import SensorBank
from desmon.sim.world import Slip

pytestmark = pytest.mark.skipif(not hasattr(os, "fork"), reason="rendering ahead forks")

#: an 11-minute mission: grasps, holds, moves and slips
_SEGS, _t = deliveries(15)
_SLIPS = [SlipEvent(s + 2.5, "down", "pulled") for c, s, _ in _SEGS if c == "hold"][::2]


def _feeds(rng: np.random.Generator) -> list[tuple[str, float, float]]:
    """What a simulation does to one detector: activations, then chunks of frames in order of
    every size (one frame to a whole block and more), and now and then a gap (frames never fed)."""
    out: list[tuple[str, float, float]] = []
    t = 0.5
    while t < _t:
        if rng.random() < 0.08:
            out.append(("activate", t, t))
        d = float(rng.choice([0.02, 0.05, 0.4, 3.0, 12.0]) * rng.uniform(0.5, 1.5))
        if rng.random() < 0.07:
            t += d  # a gap
            continue
        out.append(("feed", t, t + d))
        t += d
    return out


def _both(seed: int, gating: bool = True) -> tuple[int, int]:
    """Feed two detectors the same frames, one with the worker's hints; assert every output is
    the same bytes; return (frames fed, frames whose flow came from a hint)."""
    fast, ref = MissionSignals(_SEGS, _SLIPS, seed=9), MissionSignals(_SEGS, _SLIPS, seed=9)
    arr = fast.tactile_array
    arr.start_ahead(flow_ahead)
    hinted = TactileDetector(warmup_gating=gating)
    plain = TactileDetector(warmup_gating=gating)
    fed = 0
    try:
        for what, t0, t1 in _feeds(np.random.default_rng(seed)):
            if what == "activate":
                hinted.activate(t0)
                plain.activate(t0)
                continue
            a, b = fast.tactile(t0, t1), ref.tactile(t0, t1)
            hint = FlowHint(int(a.index[0]), a.flow) if a.flow is not None and a.index.size else None
            got = hinted.scores(a.times, a.moments, hint)
            want = plain.scores(b.times, b.moments)
            assert all(x.tobytes() == y.tobytes() for x, y in zip(got, want)), (t0, t1)
            assert hinted.status == plain.status, (t0, t1)
            fed += int(a.times.size)
    finally:
        arr.stop_ahead()
    assert plain.hinted == 0
    return fed, hinted.hinted


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_detector_fed_hints_gives_the_bytes_it_gives_without(seed: int) -> None:
    fed, hinted = _both(seed)
    assert hinted > 0.5 * fed  # the hints were really taken


def test_without_warm_up_gating_too() -> None:
    fed, hinted = _both(3, gating=False)
    assert hinted > 0.5 * fed


def test_a_hint_after_frames_not_fed_is_taken_only_past_the_first_two() -> None:
    """After a gap the detector's last frames are not the two before the hint's first, so the
    hint's first two values (worked out from those) must not be taken."""
    sig = MissionSignals(_SEGS, _SLIPS, seed=9)
    blk = sig.tactile(3.0, 12.0)  # holding: every pad in contact
    vals = flow_ahead(blk.moments[2:], blk.moments[:2])
    m, t, first = blk.moments[2:], blk.times[2:], int(blk.index[2])
    det, ref = TactileDetector(), TactileDetector()
    for d in (det, ref):
        d.activate(2.9)
    n = 60
    det.scores(t[:n], m[:n], FlowHint(first, vals[:n]))
    ref.scores(t[:n], m[:n])
    gap = n + 25  # frames n .. gap - 1 are never fed
    got = det.scores(t[gap:], m[gap:], FlowHint(first + gap, vals[gap:]))
    want = ref.scores(t[gap:], m[gap:])
    assert got[1].tobytes() == want[1].tobytes()
    assert got[1][:2].tobytes() != vals[gap : gap + 2].tobytes()  # the hint's own first two differ here
    assert det.hinted == (n - 2) + (m.shape[0] - gap - 2)


def test_a_hint_of_the_wrong_length_is_refused() -> None:
    sig = MissionSignals(_SEGS, _SLIPS, seed=9)
    blk = sig.tactile(3.0, 4.0)
    det = TactileDetector()
    det.activate(2.9)
    with pytest.raises(SignalError, match="one value per frame"):
        det.scores(blk.times, blk.moments, FlowHint(int(blk.index[0]), np.zeros(blk.times.size + 1)))


def test_the_sensor_bank_passes_a_hint_only_for_the_streams_own_frames() -> None:
    pads = [(Device(f"pad{i}", "tactile_pad", "arm"), "tactile") for i in range(6)]
    slips = [Slip(s.onset, s.direction, s.kind) for s in _SLIPS]
    bank = SensorBank(_SEGS, slips, seed=9, devices=pads)
    names = [d.name for d, _ in pads]
    bank.signals.tactile_array.start_ahead(flow_ahead)
    try:
        t, mom, hint = bank.tactile_read(3.0, 12.0, names)
        assert hint is not None and hint.values.shape == t.shape
        _t2, _m2, part = bank.tactile_read(12.0, 14.0, names[:4])  # two pads out of the graph's reach read zero
        assert part is None
        bank.fail("pad2", 15.0)
        _t3, m3, down = bank.tactile_read(14.0, 16.0, names)  # pad2 reads zero from 15 s
        assert down is None and not m3[-1, 2].any()
        _t4, _m4, later = bank.tactile_read(16.0, 17.0, names[:2] + names[3:] + names[2:3])
        assert later is None
    finally:
        bank.signals.tactile_array.stop_ahead()


class _Recorder:
    """A user's own detector over the tactile stream: records the keywords it is called with."""

    def __init__(self) -> None:
        self.calls: list[dict[str, object]] = []

    def process(self, times, samples, until=None, **hints):  # type: ignore[no-untyped-def]
        self.calls.append(hints)
        return ()


def test_a_detector_gets_only_the_hints_its_class_names() -> None:
    from desmon.sim.sensors import DetectorAdapter

    pads = [(Device(f"pad{i}", "tactile_pad", "arm"), "tactile") for i in range(6)]
    bank = SensorBank(_SEGS, [], seed=9, devices=pads)
    devices = {"tactile": [d.name for d, _ in pads]}
    bank.signals.tactile_array.start_ahead(flow_ahead)
    try:
        plain, asking = _Recorder(), _Recorder()
        asking.hints = ("tactile_flow",)  # type: ignore[attr-defined]
        for det in (plain, asking):
            adapter = DetectorAdapter(frozenset({"tactile"}), "own")
            adapter.det = det
            adapter.feed(bank, 3.0, 12.0, devices)
    finally:
        bank.signals.tactile_array.stop_ahead()
    assert plain.calls == [{}]
    (got,) = asking.calls
    assert isinstance(got["tactile_flow"], FlowHint)


@pytest.mark.parametrize(
    "build, word",
    [
        (lambda: FlowHint(-1, np.zeros(3)), "first frame -1"),
        (lambda: FlowHint(2.5, np.zeros(3)), "first frame 2.5"),  # type: ignore[arg-type]
        (lambda: FlowHint(True, np.zeros(3)), "first frame True"),
        (lambda: FlowHint(0, np.zeros((3, 2))), "shape (3, 2)"),
        (lambda: FlowHint(0, ["a", "b"]), "type list"),  # type: ignore[arg-type]
        (lambda: TactileDetector().scores(np.zeros(2), np.zeros((2, 6, 3)), [0.0, 0.0]), "type list"),  # type: ignore[arg-type]
        (lambda: flow_ahead(np.zeros((4, 6))), "moments of shape (4, 6)"),
        (lambda: flow_ahead(np.zeros((4, 6, 3)), np.zeros((3, 6, 3))), "3 frames before"),
    ],
)
def test_a_malformed_hint_is_refused_in_one_line(build, word) -> None:  # type: ignore[no-untyped-def]
    assert word in refused(SignalError, build)
