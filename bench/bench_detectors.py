"""Slip-detector benchmarks: evaluation throughput and signal/detector cost per simulated second.

Each figure comes with a plain-numpy baseline measured in the same run, of the same
sample count: Gaussian noise for every wrench sample and every tactile cell (6 pads x
14 x 6 per frame) plus a threshold test, vectorised the same way (whole batch for the
evaluation; 1 s blocks for the mission stream). Ratios are ours / baseline time.

    python -m bench.bench_detectors [--trials N] [--hours H] [--seed S]

Last line: ``RESULT trials_per_s=<evaluation> eval_ratio=<ours / baseline> missions_per_s=<missions>
detectors_us_per_sim_s=<the three detectors per simulated s, the worse of the two days>``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from desmon.detectors.combined import CombinedDetector
from desmon.detectors.evaluation import ACTION_DURATION, P1_ACTIONS, PRE, evaluate_actions, evaluate_missions
from desmon.detectors.force import ForceDetector
from desmon.detectors.signals import MissionSignals
from desmon.detectors.tactile import TactileDetector

CELLS = 6 * 14 * 6


def _baseline_eval(trials: int, rng: np.random.Generator) -> float:
    t0 = time.perf_counter()
    for action in P1_ACTIONS:
        dur = PRE + ACTION_DURATION[action]
        kf, kt = int(dur * 50), int(dur * 30) + 1
        for start in range(0, trials, 200):
            n = min(200, trials - start)
            w = rng.standard_normal((n, kf))
            tac = rng.standard_normal((n, kt, CELLS))
            _ = (np.abs(w) > 1.5).any(axis=1), (tac > 3.0).any(axis=(1, 2))
    return time.perf_counter() - t0


def _day(hours: float) -> list[tuple[str, float, float]]:
    """A robot day: every 10 min a delivery (grasp, hold, move_base, hold, release), idle otherwise."""
    segs: list[tuple[str, float, float]] = []
    t = 0.0
    end = hours * 3600.0
    while t + 600.0 <= end:
        segs += [("idle", t, 560.0), ("grasp", t + 560, 2.0), ("hold", t + 562, 20.0), ("move_base", t + 582, 3.7),
                 ("hold", t + 585.7, 10.0), ("release", t + 595.7, 4.3)]
        t += 600.0
    if t < end:
        segs.append(("idle", t, end - t))
    return segs


def _hold_day(hours: float) -> list[tuple[str, float, float]]:
    """Worst case for the tactile stream: the object is held all day (one long hold)."""
    return [("grasp", 0.0, 2.0), ("hold", 2.0, hours * 3600.0 - 2.0)]


def _stream(segs: list[tuple[str, float, float]], seconds: float, seed: int, block: float = 1.0) -> tuple[float, float]:
    ms = MissionSignals(segs, [], seed=seed)
    dets = (ForceDetector(), TactileDetector(), CombinedDetector())
    for d in dets:
        d.activate(0.0)
    gen = det = 0.0
    for k in range(int(seconds / block)):
        a, b = k * block, (k + 1) * block
        t0 = time.perf_counter()
        w, tb = ms.wrench(a, b), ms.tactile(a, b)
        t1 = time.perf_counter()
        dets[0].process(w.times, w.values, until=b)
        dets[1].process(tb.times, tb.moments, until=b)
        dets[2].process(w.times, w.values, tb.times, tb.moments, until=b)
        det += time.perf_counter() - t1
        gen += t1 - t0
    return gen, det


def _baseline_stream(seconds: float, rng: np.random.Generator) -> float:
    t0 = time.perf_counter()
    for _ in range(int(seconds)):
        w = rng.standard_normal(50)
        tac = rng.standard_normal((30, CELLS))
        _ = (np.abs(w) > 1.5).any(), (tac > 3.0).any()
    return time.perf_counter() - t0


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--trials", type=int, default=300, help="trials per action (default 300)")
    ap.add_argument("--hours", type=float, default=1.0, help="simulated hours of mission stream (default 1)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--block", type=float, default=1.0, help="request block length in s (default 1)")
    args = ap.parse_args([] if argv is None else argv)
    rng = np.random.default_rng(args.seed)

    t0 = time.perf_counter()
    evaluate_actions(args.trials, args.seed)
    t_eval = time.perf_counter() - t0
    n_trials = args.trials * len(P1_ACTIONS)
    t_base = _baseline_eval(args.trials, rng)
    print(f"evaluation, Tables 1-2: {n_trials} trials in {t_eval:.2f} s = {n_trials / t_eval:,.0f} trials/s (1 process)")
    print(f"  baseline (noise + threshold, same sample count): {t_base:.2f} s; ratio {t_eval / t_base:.2f}x")
    t0 = time.perf_counter()
    evaluate_missions(args.trials, args.seed)
    t_mis = time.perf_counter() - t0
    print(f"evaluation, missions: {4 * args.trials} missions (7.7 s each) in {t_mis:.2f} s = {4 * args.trials / t_mis:,.0f} missions/s")

    seconds = args.hours * 3600.0
    t_sbase = _baseline_stream(seconds, rng)
    det_us = []
    for label, segs in (("delivery day (mostly idle, a delivery every 10 min)", _day(args.hours)),
                        ("holding all day (worst case for tactile)", _hold_day(args.hours))):
        gen, det = _stream(segs, seconds, args.seed, args.block)
        print(f"mission stream, {label}, {args.hours:g} h in {args.block:g} s blocks:")
        print(f"  signal generation {1e6 * gen / seconds:7.1f} us per simulated s "
              f"(ratio {gen / t_sbase:.2f}x baseline {1e6 * t_sbase / seconds:.1f} us/s); 8 h day: {8 * 3600 * gen / seconds:.2f} s")
        print(f"  3 detectors       {1e6 * det / seconds:7.1f} us per simulated s "
              f"(ratio {det / t_sbase:.2f}x); 8 h day: {8 * 3600 * det / seconds:.2f} s")
        det_us.append(1e6 * det / seconds)
    print(f"RESULT trials_per_s={n_trials / t_eval:.0f} eval_ratio={t_eval / t_base:.2f} missions_per_s={4 * args.trials / t_mis:.0f} "
          f"detectors_us_per_sim_s={max(det_us):.1f}")


if __name__ == "__main__":
    import sys

    main(sys.argv[1:])
