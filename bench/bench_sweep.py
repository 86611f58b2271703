"""Sweep throughput on Dask: ``python -m bench.bench_sweep`` (needs the sweep extra).

200 runs of the robot day (scenarios/robot_day.py shortened to ``--hours``; 4
hand_pc memories x 5 wrench MTTFs x 10 seeds), measured three ways in the same run:

* a bare loop: :func:`desmon.sweep.jobs.run_point` called 200 times in this process;
* a local Dask cluster of 1 worker process, through :func:`desmon.sweep.runner.execute`
  (the code ``desmon sweep`` runs);
* a local Dask cluster of 2 worker processes.

Each cluster is started and warmed up (one run per worker: imports, scenario loading)
before the clock starts, so the figures are the steady state of a long sweep; the start
itself is printed separately. Speed-up: 1-worker time / 2-worker time (goal >= 1.8 on 2
idle cores). Overhead: (1-worker time - bare loop time) / bare loop time (goal < 5 %).
The rows of the three are checked equal (wall_s aside). Last line:
``RESULT speedup=<x> overhead=<fraction> ...``.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCENARIO = ROOT / "scenarios" / "robot_day.py"


def _runs(hours: float, seeds: int):  # type: ignore[no-untyped-def]
    from desmon.sweep.grid import Grid, parse_axes

    axes = parse_axes(["hand_memory=256,320,384,512", "wrench_mttf=600,1200,1800,3600,7200", f"hours={hours}"])
    return list(Grid(axes, seeds, 0).runs())


def _dask(spec, runs, workers: int) -> tuple[float, float, dict]:  # type: ignore[no-untyped-def]
    """(start seconds, sweep seconds, rows by key) on a fresh LocalCluster of ``workers``."""
    import logging

    from distributed import Client, LocalCluster

    from desmon.sweep.jobs import run_point
    from desmon.sweep.runner import execute

    import dask

    from desmon.sweep.runner import dask_settings

    t0 = time.perf_counter()
    with dask.config.set(dask_settings()):  # the configuration `desmon sweep` starts its cluster with
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0",
                               silence_logs=logging.CRITICAL)
    try:
        with Client(cluster, set_as_default=False) as client:  # warm-up: one run on every worker
            addresses = list(client.scheduler_info()["workers"])
            warm = [client.submit(run_point, spec, runs[i], workers=[a], pure=False) for i, a in enumerate(addresses)]
            client.gather(warm)
        started = time.perf_counter() - t0
        rows: dict = {}
        t1 = time.perf_counter()
        execute(spec, runs, lambda run, row: rows.__setitem__(run.key, row), scheduler=cluster.scheduler_address)
        return started, time.perf_counter() - t1, rows
    finally:
        cluster.close()


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m bench.bench_sweep")
    ap.add_argument("--hours", type=float, default=0.5, help="length of each robot day (h)")
    ap.add_argument("--seeds", type=int, default=10, help="seeds per point (20 points)")
    args = ap.parse_args(argv)
    from desmon.sweep.jobs import JobSpec, run_point

    spec = JobSpec("run", str(SCENARIO), "desmon", (("until", None),))
    runs = _runs(args.hours, args.seeds)
    run_point(spec, runs[0])  # warm-up: imports and the first scenario load
    t0 = time.perf_counter()
    bare = {run.key: run_point(spec, run) for run in runs}
    t_bare = time.perf_counter() - t0
    start1, t1, one = _dask(spec, runs, 1)
    start2, t2, two = _dask(spec, runs, 2)

    def same(a: dict, b: dict) -> bool:
        strip = lambda rows: {k: {c: v for c, v in r.items() if c != "wall_s"} for k, r in rows.items()}  # noqa: E731
        return strip(a) == strip(b)

    assert same(bare, one) and same(bare, two), "the rows differ between the bare loop and Dask"
    failed = sum(1 for r in bare.values() if r.get("error"))
    speedup = t1 / t2
    overhead = (t1 - t_bare) / t_bare
    n = len(runs)
    print(f"{n} runs of robot_day ({args.hours:g} h each), {failed} failed; {os.cpu_count()} cores; load average "
          f"{os.getloadavg()[0]:.2f}")
    print(f"  bare loop (this process)      {t_bare:7.2f} s   {1000 * t_bare / n:6.1f} ms/run")
    print(f"  Dask, 1 worker process        {t1:7.2f} s   {1000 * t1 / n:6.1f} ms/run   (cluster start + warm-up {start1:.1f} s)")
    print(f"  Dask, 2 worker processes      {t2:7.2f} s   {1000 * t2 / n:6.1f} ms/run   (cluster start + warm-up {start2:.1f} s)")
    print(f"  speed-up 2 vs 1 workers: {speedup:.2f}x (goal >= 1.8 on 2 idle cores); "
          f"Dask overhead vs the bare loop: {100 * overhead:+.1f} % (goal < 5 %), {1000 * (t1 - t_bare) / n:+.1f} ms/task")
    print(f"RESULT speedup={speedup:.3f} overhead={overhead:.4f} runs={n} hours={args.hours:g} bare_s={t_bare:.2f} "
          f"one_worker_s={t1:.2f} two_workers_s={t2:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
