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
    ap.add_argument("--scheduler", metavar="ADDRESS", help="compare a running Dask cluster (e.g. tcp://127.0.0.1:8786, "
                    "started as docs/sweeps.md says) with a local cluster of as many single-threaded workers, per task")
    ap.add_argument("--rounds", type=int, default=3, help="with --scheduler: turns each cluster takes (medians reported)")
    args = ap.parse_args(argv)
    from desmon.sweep.jobs import JobSpec, run_point

    spec = JobSpec("run", str(SCENARIO), "desmon", (("until", None),))
    runs = _runs(args.hours, args.seeds)
    if args.scheduler:
        return _against_cluster(spec, runs, args)
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


def _warm_cluster(spec, runs, address: str) -> tuple[int, int]:  # type: ignore[no-untyped-def]
    """Run one task on every worker of the cluster at ``address``; (workers, threads)."""
    from distributed import Client

    from desmon.sweep.jobs import run_point

    with Client(address, set_as_default=False) as client:
        info = client.scheduler_info()["workers"]
        warm = [client.submit(run_point, spec, runs[i % len(runs)], workers=[a], pure=False) for i, a in enumerate(info)]
        client.gather(warm)
        return len(info), sum(w.get("nthreads", 1) for w in info.values())


def _timed(spec, run):  # type: ignore[no-untyped-def]
    """run_point, plus the CPU seconds of the thread that ran it (``cpu_s``): what the task
    itself cost, whatever else the machine was doing. (Defined in the module run as
    ``__main__``, so Dask ships it by value to workers that cannot import ``bench``.)"""
    import time as _time

    from desmon.sweep.jobs import run_point

    c0 = _time.thread_time()
    row = run_point(spec, run)
    return {**row, "cpu_s": _time.thread_time() - c0}


def _per_task(spec, runs, address: str) -> tuple[float, float, float, dict]:  # type: ignore[no-untyped-def]
    """(sweep seconds, mean in-task wall seconds, mean in-task CPU seconds, rows) of ``runs``
    through desmon's sweep runner on the cluster at ``address``."""
    from desmon.sweep.runner import execute

    rows: dict = {}
    t0 = time.perf_counter()
    execute(spec, runs, lambda run, row: rows.__setitem__(run.key, row), scheduler=address, task=_timed)
    wall = time.perf_counter() - t0
    n = len(rows)
    return wall, sum(r["wall_s"] for r in rows.values()) / n, sum(r["cpu_s"] for r in rows.values()) / n, rows


def _against_cluster(spec, runs, args) -> int:  # type: ignore[no-untyped-def]
    """The per-task time of a running cluster against a local cluster of as many
    single-threaded workers (the cluster ``desmon sweep`` starts), in the same run: the
    two take turns, ``--rounds`` times each (the order alternating), and each figure is
    the median over the rounds, so that a change in the machine's other load between two
    turns does not decide the ratio."""
    import logging
    import statistics

    import dask
    from distributed import LocalCluster

    from desmon.sweep.runner import dask_settings

    workers, threads = _warm_cluster(spec, runs, args.scheduler)
    with dask.config.set(dask_settings()):
        local = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0",
                             silence_logs=logging.CRITICAL)
    strip = lambda rows: {k: {c: v for c, v in r.items() if c not in ("wall_s", "cpu_s")} for k, r in rows.items()}  # noqa: E731
    figures: dict[str, list[tuple[float, float, float]]] = {"local": [], "cluster": []}
    try:
        _warm_cluster(spec, runs, local.scheduler_address)
        reference = None
        for r in range(args.rounds):
            turns = [("local", local.scheduler_address), ("cluster", args.scheduler)]
            for name, address in turns if r % 2 == 0 else turns[::-1]:
                wall, task_wall, task_cpu, rows = _per_task(spec, runs, address)
                reference = reference or strip(rows)
                assert strip(rows) == reference, "the rows differ between the local cluster and the given one"
                figures[name].append((wall * workers / len(runs), task_wall, task_cpu))
                print(f"  round {r + 1} {name:7s}: {1000 * wall * workers / len(runs):7.1f} ms per task of sweep wall, "
                      f"{1000 * task_wall:7.1f} ms in the task, {1000 * task_cpu:7.1f} ms CPU; load {os.getloadavg()[0]:.2f}", flush=True)
    finally:
        local.close()
    n = len(runs)
    med = {k: [statistics.median(f[i] for f in v) for i in range(3)] for k, v in figures.items()}
    ratios = [statistics.median(c[i] / l[i] for l, c in zip(figures["local"], figures["cluster"])) for i in range(3)]
    print(f"{n} runs of robot_day ({args.hours:g} h each), {args.rounds} rounds; {os.cpu_count()} cores; "
          f"load average {os.getloadavg()[0]:.2f}")
    for name, label in (("local", f"local cluster, {workers} single-threaded workers"),
                        ("cluster", f"{args.scheduler}: {workers} workers, {threads} threads")):
        per, wall, cpu = med[name]
        print(f"  {label:48s} per task: {1000 * per:7.1f} ms of sweep wall x workers, {1000 * wall:7.1f} ms in the task, "
              f"{1000 * cpu:7.1f} ms CPU (medians)")
    print(f"  the given cluster / the local one, per task (median of the rounds' ratios): {ratios[0]:.3f} sweep wall, "
          f"{ratios[1]:.3f} in-task wall, {ratios[2]:.3f} in-task CPU (goal: within 10 %)")
    print(f"RESULT per_task_ratio={ratios[0]:.3f} in_task_ratio={ratios[1]:.3f} cpu_ratio={ratios[2]:.3f} runs={n} "
          f"hours={args.hours:g} rounds={args.rounds} workers={workers} threads={threads}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
