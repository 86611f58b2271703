"""Simulated seconds per wall second of the robot-day scenario (signals and detectors on).

Baseline: the same run's SimPy events replayed on a bare ``simpy.Environment`` (one
timeout per event the real run scheduled), i.e. what SimPy alone costs for that event
count. Reported: sim-s / wall-s, the real-time factor, and real run time / bare time;
also the same day with signals off (deployment core, repository, audit and SimPy only).
Goal: the 8 h day in under 6 s wall (>= 5,000x real time).

Measured on the shared 2-core machine (other jobs busy on both cores, so +-10 %),
seed 0, ``python -m bench.bench_sim``:

=====================================  =================  ==================
                                        before (e949c5d)   now
=====================================  =================  ==================
robot day, 28,800 sim-s, wall           7.6-9.0 s          4.2-4.4 s
sim-s per wall-s (x real time)          3,800x             6,600-6,900x
SimPy events                            39,281             25,136
ratio full run / bare SimPy (same ev.)  254x               180-235x
same day, signals off                   ~0.9 s             ~0.9 s
=====================================  =================  ==================

Where the time goes now (in-process, ~4 s): tactile rendering ~1.6 s (20.6 M cells
above the dead-band, 447 k frames: every cell needs its own normal; values are kept
bit-identical to the pad-by-pad reference), deployment core + repository + audit +
SimPy ~1.0-1.4 s (3,523 reactions, all audited), wrench rendering ~0.35 s, detector
scoring ~0.4 s. ``desmon run`` adds ~0.4 s of interpreter start-up.

Run: ``python -m bench.bench_sim [--until SECONDS] [--seed S]``.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import simpy

from desmon.loader import load_scenario
from desmon.sim.engine import SimWorld

ROOT = Path(__file__).resolve().parents[1]


def _bare(n_events: int) -> float:
    env = simpy.Environment()

    def proc():
        for _ in range(n_events):
            yield env.timeout(0.01)

    env.process(proc())
    t0 = time.perf_counter()
    env.run()
    return time.perf_counter() - t0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m bench.bench_sim")
    ap.add_argument("--until", type=float, default=None, help="simulated seconds (default: the 8 h day)")
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args(argv)
    sc = load_scenario(ROOT / "scenarios" / "robot_day.py")
    w = SimWorld(sc, seed=a.seed, until=a.until)
    counter = {"n": 0}
    step = w.env.step

    def counted() -> None:
        counter["n"] += 1
        step()

    w.env.step = counted  # type: ignore[method-assign]
    t0 = time.perf_counter()
    r = w.run()
    wall = time.perf_counter() - t0
    bare = _bare(counter["n"])
    w0 = SimWorld(sc, seed=a.seed, until=a.until, signals=False)
    t1 = time.perf_counter()
    w0.run()
    off = time.perf_counter() - t1
    sim = r.horizon
    print(f"robot day: {sim:.0f} sim-s in {wall:.2f} s wall -> {sim / wall:,.0f} sim-s per wall-s ({sim / wall:,.0f}x real time)")
    print(f"  SimPy events: {counter['n']:,}; samples wrench {r.metrics['samples']['wrench']:,}, tactile {r.metrics['samples']['tactile']:,}")
    print(f"  bare SimPy, same event count: {bare:.3f} s -> {counter['n'] / bare:,.0f} events/s")
    print(f"  ratio (full run wall / bare SimPy wall): {wall / bare:.1f}x;  goal 8 h in < 6 s: {'met' if wall < 6 and sim >= 28800 else 'NOT met'}")
    print(f"  same run with signals off: {off:.2f} s wall (deployment core, repository, audit, SimPy)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
