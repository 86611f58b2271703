"""Simulated seconds per wall second of the robot-day scenario (signals and detectors on).

Baseline: the same run's SimPy events replayed on a bare ``simpy.Environment`` (one
timeout per event the real run scheduled), i.e. what SimPy alone costs for that event
count. Reported: sim-s / wall-s, the real-time factor, and real run time / bare time.
Goal: the 8 h day in under 6 s wall (>= 5,000x real time).

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
    sim = r.horizon
    print(f"robot day: {sim:.0f} sim-s in {wall:.2f} s wall -> {sim / wall:,.0f} sim-s per wall-s ({sim / wall:,.0f}x real time)")
    print(f"  SimPy events: {counter['n']:,}; samples wrench {r.metrics['samples']['wrench']:,}, tactile {r.metrics['samples']['tactile']:,}")
    print(f"  bare SimPy, same event count: {bare:.3f} s -> {counter['n'] / bare:,.0f} events/s")
    print(f"  ratio (full run wall / bare SimPy wall): {wall / bare:.1f}x;  goal 8 h in < 6 s: {'met' if wall < 6 and sim >= 28800 else 'NOT met'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
