"""Signal models: determinism, chunk invariance, layout, faults, input validation."""

from __future__ import annotations

import re
import numpy as np
import pytest

from desmon.detectors.signals import (
    MAX_ROWS,
    PAD_ROWS,
    MissionSignals,
    Segment,
    SensorFault,
    SlipEvent,
    frame_moments,
)
from desmon.errors import SignalError

MISSION = [
    ("idle", 0.0, 1.0),
    ("grasp", 1.0, 2.0),
    ("hold", 3.0, 2.0),
    ("move_base", 5.0, 3.7),
    ("rotate_cw", 8.7, 1.5),
    ("release", 10.2, 1.2),
    ("idle", 11.4, 2.0),
]
SLIPS = [SlipEvent(4.2, "down", "pulled"), SlipEvent(7.0, "down", "gravitational")]


def _make(seed: int = 7, **kw: object) -> MissionSignals:
    return MissionSignals(MISSION, SLIPS, seed=seed, **kw)  # type: ignore[arg-type]


def test_chunked_generation_equals_one_shot_generation() -> None:
    whole_w = _make().wrench(0.0, 13.4)
    whole_t = _make().tactile(0.0, 13.4, frames=True)
    ms = _make()
    edges = [0.0, 0.013, 1.0, 1.5, 2.77, 4.2, 4.21, 9.0, 10.0, 13.4]
    ws = [ms.wrench(a, b) for a, b in zip(edges, edges[1:])]
    ts = [ms.tactile(a, b, frames=True) for a, b in zip(edges[::-1][1:], edges[::-1])][::-1]  # reverse order too
    assert np.array_equal(np.concatenate([w.values for w in ws]), whole_w.values)
    assert np.array_equal(np.concatenate([w.times for w in ws]), whole_w.times)
    assert np.array_equal(np.concatenate([t.times for t in ts]), whole_t.times)
    assert np.array_equal(np.concatenate([t.moments for t in ts]), whole_t.moments)
    assert np.array_equal(np.concatenate([t.frames for t in ts]), whole_t.frames)  # type: ignore[misc]


@pytest.mark.parametrize("rate", [50.0, 1000.0])
def test_a_wrench_sample_reads_the_same_bytes_whether_its_block_is_rendered_whole_or_in_part(rate: float) -> None:
    # a request by time renders only its own samples of a block; an index request the whole block
    source = "lwr_estimate" if rate == 50.0 else "wrist_ft"
    whole = _make(wrench_source=source, wrench_rate=rate)
    n = int(13.4 * rate)
    scattered = np.arange(n)[::-1].copy()  # not consecutive: whole blocks, cached
    reference = whole.wrench_at(scattered).values[::-1]
    parts = _make(wrench_source=source, wrench_rate=rate)
    rng = np.random.default_rng(0)
    edges = np.unique(np.concatenate([[0.0, 13.4], rng.uniform(0.0, 13.4, 40)]))
    values = np.concatenate([parts.wrench(a, b).values for a, b in zip(edges, edges[1:])])
    assert values.size == n
    assert np.array_equal(values.view(np.int64), reference.view(np.int64))  # bit for bit


def test_same_seed_gives_identical_signals_and_another_seed_does_not() -> None:
    a, b, c = _make(3), _make(3), _make(4)
    assert np.array_equal(a.wrench(0, 13).values, b.wrench(0, 13).values)
    assert np.array_equal(a.tactile(0, 13).moments, b.tactile(0, 13).moments)
    assert not np.array_equal(a.wrench(0, 13).values, c.wrench(0, 13).values)


def test_frames_use_the_documented_pad_layout_and_match_the_moments() -> None:
    tb = _make().tactile(0.0, 13.4, frames=True)
    assert tb.frames is not None and tb.frames.shape[1:] == (6, MAX_ROWS, 6)
    for pad, rows in enumerate(PAD_ROWS):
        if rows == 13:
            assert not tb.frames[:, pad, 13, :].any()
    assert tb.frames.max() <= 3500 and tb.frames.min() >= 0
    assert np.array_equal(frame_moments(tb.frames), tb.moments)


def test_hand_is_empty_in_idle_and_touched_while_holding() -> None:
    ms = _make()
    assert not ms.tactile(0.0, 1.0).moments.any()
    assert not ms.tactile(12.0, 13.4).moments.any()
    assert (ms.tactile(3.0, 4.0).moments[:, :, 0] > 0).sum(axis=1).min() >= 2


def test_tactile_frames_come_at_about_30_hz_in_order() -> None:
    t = _make().tactile(0.0, 13.4).times
    d = np.diff(t)
    assert d.min() > 0.015 and abs(np.median(d) - 1 / 30) < 0.003 and np.std(d) > 0.001


def test_wrench_sample_grid_follows_the_rate() -> None:
    assert _make().wrench(0.0, 1.0).times.size == 50
    assert _make(wrench_source="wrist_ft", wrench_rate=500.0).wrench(0.0, 1.0).times.size == 500


def test_silent_fault_removes_samples_and_zero_fault_outputs_zero() -> None:
    ms = _make(faults=[SensorFault("wrench", 5.0, "silent", 6.0), SensorFault("tactile", 3.5, "zero")])
    w = ms.wrench(4.0, 7.0)
    assert not ((w.times >= 5.0) & (w.times < 6.0)).any() and w.times.size == 100
    assert not ms.tactile(3.5, 5.0).moments.any()


def test_stuck_fault_repeats_the_last_good_sample() -> None:
    ms = _make(faults=[SensorFault("wrench", 6.0, "stuck"), SensorFault("tactile", 4.0, "stuck")])
    v = ms.wrench(5.9, 7.0).values
    assert np.all(v[5:] == v[4]) and v[4] != v[3]
    m = ms.tactile(4.0, 5.0).moments
    assert np.all(m == m[0]) and m[0, :, 0].any()


def test_gravitational_slip_unloads_the_wrist_while_a_pulled_slip_down_loads_it() -> None:
    base = [("grasp", 0.0, 2.0), ("hold", 2.0, 3.0)]
    pulled = MissionSignals(base, [(3.0, "down", "pulled")], seed=2)
    grav = MissionSignals(base, [(3.0, "down", "gravitational")], seed=2)
    quiet = MissionSignals(base, [], seed=2)
    q = quiet.wrench(2.9, 3.1).values
    assert (pulled.wrench(2.9, 3.1).values - q).mean() < -0.5
    assert (grav.wrench(2.9, 3.1).values - q)[5:].mean() > 0.2
    assert pulled.slip_truth[0].force_sign == -1 and grav.slip_truth[0].force_sign == +1


@pytest.mark.parametrize(
    ("segments", "slips", "kw", "needle"),
    [
        ([("dance", 0.0, 1.0)], [], {}, "dance"),
        ([("hold", 0.0, -1.0)], [], {}, "-1.0"),
        ([("hold", 0.0, 2.0), ("grasp", 1.0, 2.0)], [], {}, "before the previous"),
        ([("idle", 0.0, 2.0)], [(1.0, "down", "pulled")], {}, "no object"),
        ([("hold", 0.0, 2.0)], [(1.0, "sideways", "pulled")], {}, "sideways"),
        ([("hold", 0.0, 2.0)], [], {"wrench_source": "wrist_ft", "wrench_rate": 20.0}, "20.0"),
        ([("hold", 0.0, 2.0)], [], {"wrench_source": "magic"}, "magic"),
        ([("hold", 0.0, 2.0)], [], {"seed": -1}, "-1"),
    ],
)
def test_bad_signal_parameters_raise_a_signal_error_naming_the_value(
    segments: list, slips: list, kw: dict, needle: str
) -> None:
    with pytest.raises(SignalError, match=needle):
        MissionSignals(segments, slips, **kw)


def test_segments_accept_dataclasses_and_tuples_alike() -> None:
    a = MissionSignals([Segment("hold", 0.0, 2.0)], [SlipEvent(1.0)], seed=1)
    b = MissionSignals([("hold", 0.0, 2.0)], [(1.0, "down", "pulled")], seed=1)
    assert np.array_equal(a.wrench(0, 2).values, b.wrench(0, 2).values)


def _reference_block(ms: MissionSignals, b: int) -> np.ndarray:
    """Block ``b``'s moments rendered the original way: episode by episode, pad by pad."""
    from desmon.detectors.signals import TACTILE_BLOCK, block_rng, episode_pad_state, render_pad_moments
    from desmon.detectors.signals.noise import STREAM_TACTILE

    k = np.arange(b * TACTILE_BLOCK, (b + 1) * TACTILE_BLOCK)
    t = ms.tactile_times(k)
    mom = np.zeros((TACTILE_BLOCK, 6, 3))
    g = block_rng(ms.seed, STREAM_TACTILE, b)
    for ep in ms.tactile_array.episodes:
        sel = np.flatnonzero((t >= ep.start) & (t < ep.end))
        if sel.size == 0:
            continue
        amp, yc, xc = episode_pad_state(t[sel][None, :], ep, ms.params)
        for pad in range(6):
            if not np.any(amp[:, :, pad] > 0):
                continue
            s, si, sj, _ = render_pad_moments(
                amp[:, :, pad], yc[:, :, pad], xc[:, :, pad], ep.contact["sy"][:, pad], ep.contact["sx"][:, pad],
                PAD_ROWS[pad], g.standard_normal, ms.params,
            )
            mom[sel, pad] = np.stack([s[0], si[0], sj[0]], axis=-1)
    return mom


def test_vectorised_rendering_is_bit_identical_to_the_pad_by_pad_reference() -> None:
    # short episodes with several per block, slips, rotations: every code path of the renderer
    segs = []
    t = 0.0
    for i in range(12):
        for ctx, d in (("idle", 0.7 + 0.1 * i), ("grasp", 1.1), ("hold", 0.9), ("move_base", 2.3), ("rotate_ccw", 1.0), ("release", 0.8)):
            segs.append((ctx, t, d))
            t += d
    slips = [SlipEvent(s + 0.3, "down", "pulled") for c, s, d in segs if c == "hold"][::2]
    ms = MissionSignals(segs, slips, seed=11)
    nblocks = int(t * 30) // 256 + 1
    got = ms.tactile_array.render_blocks(list(range(nblocks)), False)  # all blocks in one pass
    for b in range(nblocks):
        ref = _reference_block(ms, b)
        assert np.array_equal(got[b][1], ref), b
    one = MissionSignals(segs, slips, seed=11)
    for b in (nblocks - 1, 0, 2):  # one by one, out of order
        assert np.array_equal(one.tactile_array.render_blocks([b], True)[0][1], got[b][1])


def test_ascending_episode_state_is_bit_identical_to_episode_pad_state() -> None:
    # the renderer's piecewise pad states against the reference, on every episode of a
    # mission with rotations, slips, frames inside and on segment bounds, and sparse frames
    from desmon.detectors.signals.tactile_array import _ascending_state, episode_pad_state

    segs = []
    t = 0.0
    for i in range(6):
        for ctx, d in (("idle", 0.5), ("grasp", 1.1), ("hold", 0.9 + 0.1 * i), ("rotate_cw", 1.0), ("move_base", 2.3), ("release", 0.8)):
            segs.append((ctx, t, d))
            t += d
    slips = [SlipEvent(s + 0.3, "up", "gravitational") for c, s, d in segs if c == "hold"][::2]
    ms = MissionSignals(segs, slips, seed=5)
    rng = np.random.default_rng(3)
    for ep in ms.tactile_array.episodes:
        bounds = [s for _c, s, _d, _p in ep.segments] + [s + d for _c, s, d, _p in ep.segments]
        dense = np.arange(ep.start, ep.end, 1 / 30) + rng.uniform(-0.008, 0.008, int(np.ceil((ep.end - ep.start) * 30)))
        for tt in (np.sort(np.clip(dense, ep.start, np.nextafter(ep.end, 0))), np.sort(np.array(bounds[:-1])), np.sort(dense)[::7]):
            tt = tt[(tt >= ep.start) & (tt < ep.end)]
            got = _ascending_state(tt, ep, ms.params)
            ref = episode_pad_state(tt[None, :], ep, ms.params)
            assert got is not None
            for g, r in zip(got, ref):
                assert g.tobytes() == np.ascontiguousarray(r[0]).tobytes()


def test_wrench_by_index_in_any_order_across_blocks() -> None:
    # indices whose first, last and least fall in one block while others lie in later blocks
    ms = MissionSignals([("idle", 0.0, 1.0), ("grasp", 1.0, 2.0), ("hold", 3.0, 2000.0)], seed=1)
    k = np.array([5, 3000, 7, 40_000, 1024, 1023])
    got = ms.wrench_at(k)
    one_by_one = np.array([ms.wrench_at(np.array([i])).values[0] for i in k])
    assert got.index.tolist() == k.tolist() and got.values.tobytes() == one_by_one.tobytes()


@pytest.mark.parametrize("field, value, says", [
    ("peak_lo", 0.0, "must be above 0"), ("creep_tau", 0.0, "must be above 0"), ("tactile_rate", -30.0, "must be 0 or more"),
    ("slip_jerks", 0, "whole number of jerks"), ("base_settle_p", 5.0, "at most 1 (a probability)"),
    ("noise_counts", float("nan"), "finite"), ("peak_lo", 700.0, "at most peak_hi, 600.0"), ("grasp_on", (0.6, 0.2), "low at most high"),
])
def test_signal_parameters_the_model_cannot_take_are_refused_by_name(field, value, says):
    """One rule for every engine: the sweep's -p check builds the same object."""
    from desmon.detectors.signals import SignalParams
    from desmon.errors import SignalError

    with pytest.raises(SignalError, match=f"signal parameter {field} .*{re.escape(says)}"):
        SignalParams(**{field: value})
    SignalParams()  # the defaults hold
