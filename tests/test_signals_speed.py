"""Fast paths of the signal side against their references, bit for bit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from desmon.detectors.signals.noise import SEED_CHUNK, BlockStream, block_rng, tactile_normals, wrench_noise


def _same_draws(a: np.random.Generator, b: np.random.Generator) -> bool:
    x = np.concatenate([a.standard_normal(7), a.random(3), a.integers(0, 2**63, 3).astype(float)])
    y = np.concatenate([b.standard_normal(7), b.random(3), b.integers(0, 2**63, 3).astype(float)])
    return x.tobytes() == y.tobytes()


@pytest.mark.parametrize("seed, tag", [(0, 0), (0, 1), (0, 2), (0, 3), (1, 2), (12345, 7), (2**32 - 1, 2)])
def test_block_stream_draws_what_block_rng_draws(seed: int, tag: int) -> None:
    stream = BlockStream(seed, tag)
    blocks = [0, 1, 2, 5, SEED_CHUNK - 1, SEED_CHUNK, 3 * SEED_CHUNK + 17, 2**32 - 1, 2**32, 2**40 + 3, 4]
    for b in blocks:
        assert stream.generator(b).bit_generator.state == block_rng(seed, tag, b).bit_generator.state, b
        assert _same_draws(stream.generator(b), block_rng(seed, tag, b)), b


@pytest.mark.parametrize("seed", [2**32, 2**64 + 5])
def test_block_stream_large_seeds_take_the_reference(seed: int) -> None:
    stream = BlockStream(seed, 2)
    for b in (0, 3, 2**33):
        assert _same_draws(stream.generator(b), block_rng(seed, 2, b))


def test_block_stream_every_block_of_a_chunk() -> None:
    stream = BlockStream(0, 2)
    for b in range(0, 2 * SEED_CHUNK, 7):
        assert stream.generator(b).bit_generator.state == block_rng(0, 2, b).bit_generator.state


def test_noise_helpers_with_a_stream_match_without() -> None:
    s_t, s_w = BlockStream(3, 2), BlockStream(3, 1)
    for b in (0, 9, 1500):
        assert tactile_normals(3, b, 100, stream=s_t).tobytes() == tactile_normals(3, b, 100).tobytes()
        out = np.empty(50)
        tactile_normals(3, b, 50, out=out, stream=s_t)
        assert out.tobytes() == tactile_normals(3, b, 50).tobytes()
        assert wrench_noise(3, b, 0.7, 300, s_w).tobytes() == wrench_noise(3, b, 0.7, 300).tobytes()


def _run_last_reference(frames: list[np.ndarray]) -> int:
    """Frames in the last run of identical frames (``==`` per value) over the whole stream."""
    run = 0
    for i, f in enumerate(frames):
        run = run + 1 if i and bool(np.all(f == frames[i - 1])) else 1
    return run


@pytest.mark.parametrize("chunks", [[1], [2], [3], [2, 5], [10]])
@pytest.mark.parametrize("tail", [0, 1, 2, 3, 6])
@pytest.mark.parametrize("fill", [7.0, 0.0])
def test_tactile_detector_runs_of_identical_frames(chunks: list[int], tail: int, fill: float) -> None:
    """The run of identical frames (stuck / no-contact input) whatever the chunking, against a frame-by-frame count."""
    from desmon.detectors.base import DetectorState
    from desmon.detectors.tactile import TactileDetector

    rng = np.random.default_rng(tail)
    frames = [rng.uniform(1.0, 50.0, (6, 3)) for _ in range(4)] + [np.full((6, 3), fill)] * tail + [rng.uniform(1.0, 50.0, (6, 3))]
    frames += [frames[-1]] * (tail // 2)
    det = TactileDetector(stuck_frames=3)
    det.activate(0.0)
    at, i = 0, 0
    while at < len(frames):
        part = frames[at : at + chunks[i % len(chunks)]]
        i += 1
        det.scores(0.01 * np.arange(at + 1, at + 1 + len(part)), np.stack(part))
        at += len(part)
        ref = _run_last_reference(frames[:at])
        assert det._run == ref
        assert (det.status.state is DetectorState.NO_INPUT) == (ref >= 3)


def test_block_stream_falls_back_where_numpy_seeds_otherwise(monkeypatch: pytest.MonkeyPatch) -> None:
    """Should a numpy release hash seed sequences otherwise than BlockStream re-derives, the
    once-per-process check says so and every block takes block_rng: the draws never part."""
    from desmon.detectors.signals import noise

    noise._hashing_agrees.cache_clear()
    monkeypatch.setattr(noise, "_MULT_A", noise._MULT_A ^ 1)  # another hash than numpy's
    try:
        assert not noise._hashing_agrees()
        stream = BlockStream(0, 2)
        for b in (0, 5, SEED_CHUNK + 1):
            assert stream.generator(b).bit_generator.state == block_rng(0, 2, b).bit_generator.state
            assert _same_draws(stream.generator(b), block_rng(0, 2, b))
    finally:
        noise._hashing_agrees.cache_clear()
    monkeypatch.undo()
    assert noise._hashing_agrees()


_DAY = [("idle", 0.0, 1.0), ("grasp", 1.0, 2.0), ("hold", 3.0, 20.0), ("move_base", 23.0, 3.7), ("release", 26.7, 1.2), ("idle", 27.9, 2.0)]


@pytest.mark.parametrize("frames", [False, True])
def test_tactile_between_from_cached_blocks_matches_by_index(frames: bool) -> None:
    """A request by time read from the cached blocks (one run of frames) is what the frames of
    its candidates kept by time give, spans inside a block, across blocks, empty and reversed."""
    from desmon.detectors.signals import MissionSignals, SlipEvent
    from desmon.detectors.signals.common import tactile_nominal_indices

    ms = MissionSignals(_DAY, [SlipEvent(10.0, "down", "pulled")], seed=4)
    ref = MissionSignals(_DAY, [SlipEvent(10.0, "down", "pulled")], seed=4).tactile_array
    rng = np.random.default_rng(5)
    spans = [(0.0, 29.9), (8.5, 8.51), (8.52, 8.52), (9.0, 8.0), (8.5334, 8.5334 + 1 / 30)]
    spans += [(float(a), float(a + d)) for a, d in zip(rng.uniform(0.0, 29.0, 40), rng.exponential(2.0, 40))]
    for t0, t1 in spans:
        got = ms.tactile(t0, t1, frames=frames)
        cand = tactile_nominal_indices(t0, t1, ref.rate, ref.params.tactile_jitter_clip)
        t = ref.times(cand)
        want = ref.at(cand[(t >= t0) & (t < t1)], frames=frames)
        for g, w in ((got.index, want.index), (got.times, want.times), (got.moments, want.moments), (got.frames, want.frames)):
            assert (g is None) == (w is None)
            if g is not None:
                assert g.dtype == w.dtype and g.shape == w.shape and g.tobytes() == w.tobytes(), (t0, t1)


def test_wrench_request_by_time_matches_whole_blocks() -> None:
    """A request by time renders only its samples of each block it touches (one or two blocks):
    the same bytes as the whole blocks' samples."""
    from desmon.detectors.signals import MissionSignals, SlipEvent

    ms = MissionSignals(_DAY, [SlipEvent(10.0, "down", "pulled")], seed=4)
    ref = MissionSignals(_DAY, [SlipEvent(10.0, "down", "pulled")], seed=4).wrench_sensor
    for t0, t1 in ((0.0, 1.7), (19.5, 21.2), (20.0, 20.5), (10.0, 29.9), (20.48, 20.5), (3.0, 3.0)):
        got = ms.wrench(t0, t1)
        k = got.index
        assert np.array_equal(k, np.flatnonzero((np.arange(2000) / 50.0 >= t0) & (np.arange(2000) / 50.0 < t1)))
        want = np.concatenate([ref._block(int(b))[k[k // 1024 == b] - b * 1024] for b in np.unique(k // 1024)]) if k.size else np.zeros(0)
        assert got.values.tobytes() == want.tobytes(), (t0, t1)


def test_move_base_tactile_matches_context_tactile() -> None:
    # the piecewise-constant drive against the general kernel, on random drives (settle jump
    # forced on for half of them) at ascending times that include every case's bounds exactly
    from desmon.detectors.signals.common import DEFAULT_PARAMS as p
    from desmon.detectors.signals.contexts import base_duration, context_tactile, draw_context, move_base_tactile

    rng = np.random.default_rng(7)
    for trial in range(200):
        cp = draw_context("move_base", rng, 1, None, p)
        if trial % 2:
            cp["settle"] = np.ones(1)
        start, a = float(cp["start"][0]), float(cp["a_max"][0])
        ta = float(np.sqrt(p.base_leg / a))
        dur = start + base_duration(a, p) + 0.3
        edges = [start + e for e in (0.0, ta, 2 * ta, 2 * ta + p.base_pause, 3 * ta + p.base_pause, 4 * ta + p.base_pause)]
        edges += [float(cp["settle_t"][0])]
        t = np.concatenate([rng.uniform(0.0, dur, 40), edges, np.nextafter(edges, -np.inf), np.nextafter(edges, np.inf), [0.0, dur, dur]])
        t = np.sort(t.clip(0.0, dur))
        fac, dy = move_base_tactile(t, cp, p)
        rf, rdy, rdx = context_tactile("move_base", t[None, :, None], cp, p)
        assert fac.tobytes() == rf.reshape(-1).tobytes()
        assert dy.tobytes() == rdy.reshape(-1).tobytes()
        assert not rdx.any() and rdx.size == 1


def _reference_cop(moments: np.ndarray, cop: np.ndarray) -> np.ndarray:
    """c30a13d's centred_cop (every pad-frame without contact zeroed by a mask), into ``cop``."""
    from desmon.detectors.tactile import _COL_MID, _ROW_MID

    s = moments[..., 0]
    contact = s > 0
    safe = np.where(contact, s, 1.0)
    for c, mid in ((0, _ROW_MID), (1, _COL_MID)):
        part = cop[..., c]
        np.divide(moments[..., 1 + c], safe, out=part)
        part -= mid
        np.copyto(part, 0.0, where=~contact)
    return contact


def _reference_tactile_scores(moments: np.ndarray, state, gating: bool):  # type: ignore[no-untyped-def]
    """c30a13d's tactile_scores body (contact present), the reference for its shortcuts."""
    from desmon.detectors.tactile import _CELLS, WARMUP_FRAMES, TactileState

    n, k = moments.shape[:2]
    s = moments[..., 0]
    cop_ext = np.empty((n, k + 1, 6, 2))
    cop_ext[:, 0] = state.cop
    cop = cop_ext[:, 1:]
    contact = _reference_cop(moments, cop)
    idx_ext = np.empty_like(cop_ext)
    idx_ext[:, 0] = state.index
    index = idx_ext[:, 1:]
    np.add(cop, cop_ext[:, :-1], out=index)
    d = idx_ext[:, 1:] - idx_ext[:, :-1]
    d *= d
    phi = np.sqrt(d[..., 0] + d[..., 1])
    run = state.run[:, None] + np.arange(1, k + 1)[None, :]
    valid_pad = (contact & (run >= WARMUP_FRAMES)[..., None]) if gating else contact
    w = np.where(valid_pad, s / _CELLS, 0.0)
    den = w.sum(axis=-1)
    num = (phi * w).sum(axis=-1)
    valid = den > 0
    s_t = np.where(valid, num / np.where(valid, den, 1.0), 0.0)
    return s_t, valid, TactileState(cop[:, -1].copy(), index[:, -1].copy(), np.minimum(run[:, -1], 1 << 30))


@pytest.mark.parametrize("k", [1, 3, 63, 64, 65, 300, 889])
def test_tactile_scores_shortcuts_match_the_reference(k: int) -> None:
    # the warm-up shortcut (every frame past the warm-up), the all-valid division, the steady contact shortcut (pads
    # zeroed whole) and the pad sums along the frames, against the plain body, on moments
    # with pads on, off (0.0, -0.0, negative) and flickering or not, for states of every run around
    # the warm-up, both gatings, one trial and three
    from desmon.detectors.tactile import TactileState, centred_cop, tactile_scores

    rng = np.random.default_rng(k)
    for n, flicker in ((1, True), (1, False), (3, True), (3, False)):
        mom = rng.uniform(0.0, 4000.0, (n, k, 6, 3)) * 10.0 ** rng.integers(-3, 3, (n, k, 6, 1))
        mom[..., 1, :] = 0.0  # pads without contact throughout: 0, -0, negative
        mom[..., 1, 0] = -3.0
        mom[..., 4, :] = -0.0
        if flicker:
            mom[:, ::3, 2, 0] = 0.0
            mom[:, ::5, 3, :] = -0.0
        ref_cop = np.empty((n, k, 6, 2))
        _reference_cop(mom, ref_cop)
        assert centred_cop(mom)[0].tobytes() == ref_cop.tobytes()
        for run in range(5):
            st = TactileState(rng.normal(0, 2, (n, 6, 2)), rng.normal(0, 2, (n, 6, 2)), np.full(n, run, dtype=np.int64))
            for gating in (True, False):
                got = tactile_scores(mom, st, gating)
                ref = _reference_tactile_scores(mom, st, gating)
                for g, r in zip(got[:2] + (got[2].cop, got[2].index, got[2].run), ref[:2] + (ref[2].cop, ref[2].index, ref[2].run)):
                    assert g.dtype == r.dtype and g.shape == r.shape and g.tobytes() == r.tobytes()


@pytest.mark.parametrize("shape", [(1, 64, 6), (1, 889, 6), (3, 100, 6), (1, 20000, 6)])
def test_pad_sum_adds_as_numpy_sums_six_pads(shape: tuple[int, int, int]) -> None:
    # numpy's order over an axis of six (from 0.0, left to right), on magnitudes that round
    # differently in any other order, with signed zeros, infinities and NaN
    from desmon.detectors.tactile import _pad_sum

    rng = np.random.default_rng(shape[1])
    x = rng.standard_normal(shape) * 10.0 ** rng.integers(-8, 8, shape)
    x[:, ::7] = -0.0
    x[:, ::11, 0] = 0.0
    x[:, ::13, 1:] = -0.0
    x[:, ::17, 3] = np.inf
    x[:, ::19, 2] = np.nan
    assert _pad_sum(x).tobytes() == x.sum(axis=-1).tobytes()


def test_tactile_blocks_apart_render_as_one_by_one() -> None:
    # episodes longer than a block, rendered in one pass over blocks that are not neighbours,
    # in order and out of order (an episode's frames then are not one run), and block by
    # block (one run each, written in place)
    from desmon.detectors.signals import MissionSignals, SlipEvent

    segs = []
    t = 0.0
    for ctx, d in (("idle", 1.0), ("grasp", 1.1), ("hold", 3.0), ("move_base", 20.0), ("release", 0.8)) * 2:
        segs.append((ctx, t, d))
        t += d
    slips = [SlipEvent(s + 0.5, "up", "gravitational") for c, s, d in segs if c == "hold"]
    for blocks in ([0, 2, 3, 5], [5, 3, 2, 0]):
        together = MissionSignals(segs, slips, seed=4).tactile_array.render_blocks(blocks, True)
        for b, got in zip(blocks, together):
            ref = MissionSignals(segs, slips, seed=4).tactile_array.render_blocks([b], True)[0]
            for g, r in zip(got, ref):
                assert g.tobytes() == r.tobytes(), b
            assert got[1].any(), b


@pytest.mark.parametrize("seed", range(12))
def test_zoh1_shortcut_matches_its_carried_path(seed: int) -> None:
    # a new sample before every tick (the shortcut) or not, with invalid samples, NaN,
    # infinities, signed zeros and stale gaps
    from desmon.detectors.combined import _zoh1, _zoh1_carried

    rng = np.random.default_rng(seed)
    for _ in range(20):
        k = int(rng.integers(0, 12))
        t = np.sort(rng.uniform(0.0, 1.0, k))
        s = rng.choice([0.0, -0.0, 1.5, -2.0, np.nan, np.inf, -np.inf, 3.25], k)
        v = rng.random(k) < 0.8
        lo = float(t[0]) if k and rng.random() < 0.6 else -0.1
        ticks = np.sort(rng.uniform(lo, 1.2, int(rng.integers(0, 8))))
        carry = (float(rng.uniform(-0.5, 0.0)), float(rng.choice([0.0, -0.0, 1.0])), bool(rng.random() < 0.5))
        stale = float(rng.choice([0.05, 0.1, 0.3]))
        got = _zoh1(carry, t, s.copy(), v, ticks, stale)
        ref = _zoh1_carried(carry, t, s, v, ticks, stale, t.searchsorted(ticks, side="right") - 1)
        for g, r in zip(got, ref):
            assert g.dtype == r.dtype and g.shape == r.shape and g.tobytes() == r.tobytes()


@pytest.mark.parametrize("seed", range(6))
def test_force_tared_shortcut_matches_the_general_path(seed: int) -> None:
    # chunks of noise with runs of repeated (stuck) values, through the tare, with and without the shortcut
    from desmon.detectors.force import ForceDetector

    rng = np.random.default_rng(seed)
    n = 600
    t = np.arange(n) / 50.0
    vals = rng.normal(0.0, 1.0, n)
    for start in rng.integers(0, n - 20, 4):
        vals[start : start + int(rng.integers(2, 15))] = vals[start]
    vals[rng.integers(0, n, 5)] = -0.0
    cuts = np.unique(np.concatenate([[0, n], rng.integers(1, n, 40)]))
    class LongWay(ForceDetector):
        def _tared_scores(self, t, v):  # type: ignore[no-untyped-def]
            return self._general_scores(t, v, np.zeros(v.shape, dtype=bool))  # where it applies, no value repeats

    results = []
    for kind in (ForceDetector, LongWay):
        det = kind(stuck_samples=4)
        det.activate(0.1)
        out = []
        for a, b in zip(cuts[:-1], cuts[1:]):
            tt, s, valid = det.scores(t[a:b], vals[a:b])
            out.append((tt.tobytes(), s.tobytes(), valid.tobytes(), s.dtype, valid.dtype, det.status, det._run, det._last_v, det._last_t))
        results.append(out)
    assert results[0] == results[1]


def test_move_base_force_matches_context_force() -> None:
    # the wrench's drive by its pulses against the general kernel, on random drives at
    # ascending times that include every pulse's bounds exactly and the samples beside them
    from desmon.detectors.signals.common import DEFAULT_PARAMS as p
    from desmon.detectors.signals.contexts import base_duration, context_force, draw_context, move_base_force

    rng = np.random.default_rng(11)
    for trial in range(200):
        cp = draw_context("move_base", rng, 1, None, p)
        start, a = float(cp["start"][0]), float(cp["a_max"][0])
        ta = float(np.sqrt(p.base_leg / a))
        dur = start + base_duration(a, p) + 0.3
        edges = [start + e for e in (0.0, ta, 2 * ta, 2 * ta + p.base_pause, 3 * ta + p.base_pause, 4 * ta + p.base_pause)]
        t = np.concatenate([rng.uniform(0.0, dur, 60), edges, np.nextafter(edges, -np.inf), np.nextafter(edges, np.inf), [0.0, dur, dur]])
        t = np.sort(t.clip(0.0, dur))
        coupling = float(rng.choice([1.0, 0.35, -0.8]))
        got = move_base_force(t, cp, p, coupling)
        want = context_force("move_base", t[None, :], cp, p, coupling)
        assert got.shape == t.shape and got.tobytes() == want.reshape(-1).tobytes(), trial


def test_trial_force_matches_context_force_for_every_context() -> None:
    # one trial's force at 1-D times, parameters as numbers, against the general kernel
    from desmon.detectors.signals.common import DEFAULT_PARAMS as p
    from desmon.detectors.signals.contexts import context_force, draw_context, trial_force
    from desmon.errors import SignalError

    rng = np.random.default_rng(5)
    for context in ("grasp", "release", "rotate_ccw", "rotate_cw", "move_base", "hold", "idle"):
        for _ in range(40):
            cp = draw_context(context, rng, 1, None, p)
            t = np.sort(np.concatenate([rng.uniform(-0.5, 12.0, 50), [0.0, 0.0]]))
            bounds = []  # the bump's or the drive's bounds hit exactly, and the samples beside them
            for key, width in (("b0", "bw"), ("t0", "dur"), ("start", None)):
                if key in cp:
                    b = float(cp[key][0])
                    bounds += [b] if width is None else [b, b + float(cp[width][0])]
            t = np.sort(np.concatenate([t, bounds, np.nextafter(bounds, -np.inf), np.nextafter(bounds, np.inf)]))
            want = context_force(context, t[None, :], cp, p, 0.6)
            got = trial_force(context, t, cp, p, 0.6)
            assert got.shape == t.shape and got.tobytes() == np.broadcast_to(want, (1, t.size)).reshape(-1).tobytes(), context
    two = draw_context("grasp", rng, 2, None, p)
    with pytest.raises(SignalError, match="trial_force: parameters of shape .* hold 2 trials"):
        trial_force("grasp", np.zeros(3), two, p, 1.0)


def test_wrench_indices_are_the_grid_points_in_the_window() -> None:
    # against the plain reference: every k of the window it looks in with t0 <= k / rate < t1
    # (the window holds every such k, but where k / rate rounds coarser than a sample)
    from desmon.detectors.signals.common import wrench_indices

    rng = np.random.default_rng(3)
    for rate, far in ((50.0, 500.0), (37.3, 500.0), (1000.0, 500.0), (0.7, 500.0), (1000.0, 3e13)):  # far: k / rate's rounding is coarser than a sample
        for _ in range(300):
            t0 = float(rng.choice([rng.uniform(0, far), round(float(rng.uniform(0, far)) * rate) / rate]))
            t1 = t0 + float(rng.choice([rng.exponential(2.0), 0.0, 1.0 / rate, round(float(rng.uniform(0, 5)) * rate) / rate]))
            k = np.arange(max(0, math.floor(t0 * rate) - 1), math.ceil(t1 * rate) + 1)  # the window wrench_indices looks in
            want = k[(k / rate >= t0) & (k / rate < t1)]
            got = wrench_indices(t0, t1, rate)
            assert got.dtype == np.int64 and got.tolist() == want.tolist(), (rate, t0, t1)
