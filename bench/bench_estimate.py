"""``desmon estimate``'s cost: ``python -m bench.bench_estimate [--quick] [--runs M] [--until S] [--dask-runs R]``.

In one run it measures:

* runs per minute per core of the SimPy world (signals on, as ``desmon estimate`` runs
  it) on ``scenarios/robot_day.py`` and ``scenarios/coffee_shift.py``: ``M`` runs each in
  this process, CPU seconds of this process and of the render-ahead workers it forks;
* what the runs ``desmon estimate`` makes save: CPU seconds per run of each scenario, the
  whole world (every output: signals rendered ahead and detectors, audit, trace records,
  as ``desmon run`` computes it) against the run ``desmon estimate`` makes for
  ``exposure_s`` (:func:`desmon.estimate.run_value`: the world told it is read for that
  figure alone, :class:`desmon.sim.engine.SimWorld`'s ``reads``, and collected once it is
  dropped), the same seeds, ``--full-runs`` runs each way per turn, ``--turns`` turns
  alternating, the best turn of each, and their ratio;
* the runs ``desmon estimate scenarios/coffee_shift.py --within 1% --confidence 0.99``
  needs, projected from the spread of those ``M`` runs: the betting confidence sequence
  (the code ``desmon estimate`` runs, with its looks) on the range ``desmon estimate``
  takes (the task's: :func:`desmon.estimate.measures.natural_range`) fed values drawn
  from the ``M`` runs with replacement until its half-width is 1 % of the estimate, median
  of ``--draws`` projections (their range printed); beside it the same on ``[0, horizon]``,
  the same with bets sized for no particular run (docs/estimate.md, "A bounded mean"),
  the runs the normal (CLT) interval would need, ``(z s / (0.01 mean))**2``, the floor of
  any distribution-free interval on that range ``[low, high]``
  (``(high - mean) ln(1/delta) / (0.02 mean)``: in fewer runs, a world that adds a rare
  run at ``high``, raising the mean by twice the half-width, would show no such run with
  chance above delta, so no valid interval can exclude it), and the wall minutes the
  projected runs take on 2 cores at the measured rate;
* 2 Dask workers against 1: the same estimation of ``R`` one-hour coffee-shift runs (1,000
  unless given: about 30 s on one worker, so that the last batch, about 1 s, weighs little;
  ``--within`` too small to stop early) through :func:`desmon.sweep.estimate.dask_values`
  on a local cluster of 1, then 2 worker processes, each started and warmed up (one run
  per worker) before the clock starts, ``--rounds`` turns each in the order 1, 2, 2, 1
  (so that a load that drifts weighs on both; means reported); every turn's estimate is
  checked equal.

``--coverage``: instead, the coverage self-test's figures (tests/test_estimate_coverage.py):
on each analysable shipped scenario over 300 s, ``--estimations`` independent estimations
of ``--coverage-runs`` runs each on the Markov world ``desmon analyze`` solves, and how
many of them hold the chain's exact expected exposure -- the guaranteed interval, that
interval narrowed by 20 % and by half, the normal interval and the normal interval
narrowed by 20 % -- each judged by :func:`desmon.estimate.coverage.fails`. Last line
``RESULT scenarios=... estimations=... runs=... guaranteed_passed=... guaranteed_held_min=...
normal_held_min=... narrowed_normal_failed=... halved_failed=...``.

Otherwise the last line is ``RESULT robot_day_runs_per_min_core=... coffee_shift_runs_per_min_core=...
runs_needed_1pct_99=... runs_needed_horizon_range=... runs_needed_unsized_bets=... clt_runs_needed=... floor_runs=... minutes_2_cores=...
speedup=... one_worker_s=... two_workers_s=... coffee_shift_full_s=... coffee_shift_read_s=...
coffee_shift_read_ratio=... robot_day_full_s=... robot_day_read_s=... robot_day_read_ratio=...``.
"""

from __future__ import annotations

import argparse
import logging
import math
import resource
import statistics
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCENARIOS = {"robot_day": ROOT / "scenarios" / "robot_day.py", "coffee_shift": ROOT / "scenarios" / "coffee_shift.py"}


def _cpu() -> float:
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def _rate(name: str, runs: int, until: float | None) -> tuple[float, list[float], float]:
    """(runs per CPU-minute, the runs' exposures, the horizon) of ``runs`` runs of ``name``."""
    from desmon.estimate import run_seed, run_value
    from desmon.estimate.loop import world_horizon
    from desmon.loader import load_scenario

    scenario = load_scenario(SCENARIOS[name])
    horizon = world_horizon(scenario, until)
    run_value(scenario, "desmon", run_seed(99, 0), until, "exposure_s")  # warm-up: imports, caches
    c0 = _cpu()
    values = [run_value(scenario, "desmon", run_seed(0, i), until, "exposure_s") for i in range(runs)]
    cpu = _cpu() - c0
    return 60.0 * runs / cpu, values, horizon


def _against_full(name: str, runs: int, until: float | None, turns: int) -> tuple[float, float]:
    """(CPU s per run of the whole world, CPU s per run of :func:`desmon.estimate.run_value`
    for ``exposure_s``) of ``name``: ``runs`` runs each way per turn, alternating, the best
    turn of each."""
    from desmon.estimate import run_seed, run_value
    from desmon.loader import load_scenario
    from desmon.sim.engine import SimWorld

    scenario = load_scenario(SCENARIOS[name])
    ways = {
        "full": lambda seed: SimWorld(scenario, seed=seed, until=until).run().metrics["unmonitored_exposure_s"],
        "read": lambda seed: run_value(scenario, "desmon", seed, until, "exposure_s"),
    }
    best = {"full": math.inf, "read": math.inf}
    values: dict[str, list[float]] = {}
    for _ in range(turns):
        for mode, way in ways.items():
            c0 = _cpu()
            values[mode] = [way(run_seed(0, i)) for i in range(runs)]
            best[mode] = min(best[mode], (_cpu() - c0) / runs)
    assert values["full"] == values["read"], "the run read for exposure_s gave another exposure"
    return best["full"], best["read"]


def _projected(values: list[float], value_range: tuple[float, float], draws: int, confidence: float = 0.99,
               within: float = 0.01, sized: bool = True) -> list[int]:
    """Runs the betting sequence on ``value_range`` needs to reach ``within`` of the estimate, fed draws from ``values``;
    its bets sized for that half-width as ``desmon estimate`` sizes them (``sized``), or for no particular run."""
    import numpy as np

    from desmon.estimate.loop import is_look
    from desmon.stats import BettingSequence

    rng = np.random.default_rng(0)
    out = []
    for _ in range(draws):
        goal = (lambda m: within * abs(m)) if sized else None
        cs = BettingSequence(value_range[0], value_range[1], 1.0 - confidence, goal=goal)
        n = 0
        while True:
            cs.add(float(values[rng.integers(len(values))]))
            n += 1
            if is_look(n):
                iv = cs.interval()
                if iv.half_width <= within * abs(iv.estimate) or n >= 200_000:
                    break
        out.append(n)
    return out


def _dask(workers: int, runs: int, until: float) -> tuple[float, object]:
    """(seconds, estimate) of an estimation of ``runs`` coffee-shift runs on a warmed-up local cluster."""
    import dask
    from distributed import Client, LocalCluster

    from desmon.estimate import Question, estimate
    from desmon.loader import load_scenario
    from desmon.estimate.loop import RunSeeds
    from desmon.sweep.estimate import BatchSpec, dask_values, run_batch
    from desmon.sweep.runner import dask_settings

    spec = BatchSpec(str(SCENARIOS["coffee_shift"]), (), "desmon", 0, until, "exposure_s")
    with dask.config.set(dask_settings()):
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0", silence_logs=logging.CRITICAL)
    try:
        with Client(cluster, set_as_default=False) as client:  # warm-up: one run on every worker
            addresses = list(client.scheduler_info()["workers"])
            warm = RunSeeds(spec.seed).batch(10_000, len(addresses))
            client.gather([client.submit(run_batch, spec, [warm[i]], workers=[a], pure=False) for i, a in enumerate(addresses)])
        t0 = time.perf_counter()
        q = Question(within=1e-9, relative=True, confidence=0.99, max_runs=runs)
        e = estimate(load_scenario(SCENARIOS["coffee_shift"]), q, until=until, values=dask_values(spec, scheduler=cluster.scheduler_address))
        return time.perf_counter() - t0, e
    finally:
        cluster.close()


#: the analysable shipped scenarios (as tests/test_estimate_coverage.py), and the horizon of their runs
ANALYSABLE = (("coffee_shift.py", {"hours": "1"}), ("platform_crash.py", {"stochastic": "True"}), ("cloud_offload.py", {"stochastic": "True"}))
COVERAGE_HORIZON = 300.0


def _narrowed(pick, share: float):  # type: ignore[no-untyped-def]
    def narrowed(e):  # type: ignore[no-untyped-def]
        low, high = pick(e)
        centre, half = (low + high) / 2, (high - low) / 2 * share
        return centre - half, centre + half

    return narrowed


def _coverage(count: int, runs: int, names: tuple[str, ...] | None = None) -> int:
    from desmon.analyze import analyze
    from desmon.analyze.agreement import markov_scenario
    from desmon.estimate import Question
    from desmon.estimate.coverage import coverage, estimations, guaranteed
    from desmon.loader import load_scenario

    normal = lambda e: (e.approximation.low, e.approximation.high)  # noqa: E731
    kinds = {"guaranteed": guaranteed, "guaranteed x0.8": _narrowed(guaranteed, 0.8), "guaranteed x0.5": _narrowed(guaranteed, 0.5),
             "normal": normal, "normal x0.8": _narrowed(normal, 0.8)}
    cases = [c for c in ANALYSABLE if names is None or c[0] in names]
    held: dict[str, list[int]] = {k: [] for k in kinds}
    failed: dict[str, int] = dict.fromkeys(kinds, 0)
    for name, params in cases:
        scenario = load_scenario(ROOT / "scenarios" / name, params)
        exact = analyze(scenario, miss={}, horizon=COVERAGE_HORIZON, steady=False).exposure_s_per_mission
        found = estimations(markov_scenario(scenario), Question(within=0.5, confidence=0.95, max_runs=runs), count=count, until=COVERAGE_HORIZON)
        for kind, pick in kinds.items():
            c = coverage(found, exact, pick)
            held[kind].append(c.inside)
            failed[kind] += c.failed
            print(f"{name} {params}: {kind:<16} {c}")
    print(
        f"RESULT scenarios={len(cases)} estimations={count} runs={runs} guaranteed_passed={len(cases) - failed['guaranteed']} "
        f"guaranteed_held_min={min(held['guaranteed'])} narrowed_held_min={min(held['guaranteed x0.8'])} "
        f"normal_held_min={min(held['normal'])} narrowed_normal_failed={failed['normal x0.8']} halved_failed={failed['guaranteed x0.5']}"
    )
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m bench.bench_estimate")
    ap.add_argument("--quick", action="store_true", help="a smoke run: 3 runs of 10 min per scenario, 8 Dask runs of 10 min")
    ap.add_argument("--runs", type=int, default=20, help="runs per scenario for the rate and the spread")
    ap.add_argument("--until", type=float, default=None, help="simulated seconds per run (unset: each scenario's 8 h)")
    ap.add_argument("--draws", type=int, default=5, help="projections of the runs needed")
    ap.add_argument("--dask-runs", type=int, default=1000, help="runs of the Dask comparison (1,000 one-hour runs: about 30 s on one worker, so that the last batch of 1 s weighs little)")
    ap.add_argument("--dask-until", type=float, default=3600.0, help="simulated seconds per run of the Dask comparison")
    ap.add_argument("--rounds", type=int, default=2, help="turns of each cluster size, in the order 1, 2, 2, 1 (means reported)")
    ap.add_argument("--turns", type=int, default=3, help="turns of the whole world against the run read for exposure_s (best taken)")
    ap.add_argument("--full-runs", type=int, default=3, help="runs per scenario and turn of that comparison")
    ap.add_argument("--coverage", action="store_true", help="instead, the coverage self-test's figures")
    ap.add_argument("--estimations", type=int, default=200, help="--coverage: estimations per scenario")
    ap.add_argument("--coverage-runs", type=int, default=4, help="--coverage: runs per estimation")
    ap.add_argument("--scenario", action="append", default=None, help="--coverage: only this analysable scenario (repeatable)")
    args = ap.parse_args(argv)
    counts = ("runs", "draws", "dask_runs", "rounds", "turns", "full_runs", "estimations", "coverage_runs")
    for name in counts:
        if getattr(args, name) < 1:
            ap.error(f"--{name.replace('_', '-')} {getattr(args, name)}: give a whole number, 1 or more")
    for name in ("until", "dask_until"):
        value = getattr(args, name)
        if value is not None and not (math.isfinite(value) and value > 0):
            ap.error(f"--{name.replace('_', '-')} {value}: give a positive number of simulated seconds")
    if args.coverage:
        return _coverage(args.estimations, args.coverage_runs, tuple(args.scenario) if args.scenario else None)
    if args.quick:
        args.runs, args.until, args.draws, args.dask_runs, args.dask_until, args.rounds = 3, 600.0, 1, 8, 600.0, 1
        args.turns, args.full_runs = 1, 1
    against: dict[str, tuple[float, float]] = {}
    for name in SCENARIOS:
        full, read = against[name] = _against_full(name, args.full_runs, args.until, args.turns)
        print(f"{name}: {full:.3f} CPU s per run of the whole world, {read:.3f} read for exposure_s alone ({full / read:.1f}x; "
              f"{args.full_runs} runs each way, best of {args.turns} alternating turns)")
    rates = {}
    for name in SCENARIOS:
        rate, values, horizon = _rate(name, args.runs, args.until)
        rates[name] = rate
        print(f"{name}: {rate:.1f} runs per CPU-minute ({args.runs} runs of {horizon:g} s); exposure mean {statistics.mean(values):.1f} s, "
              f"range {min(values):.1f}..{max(values):.1f}")
    from scipy.stats import norm

    from desmon.estimate.measures import natural_range
    from desmon.loader import load_scenario

    mean, sd = statistics.mean(values), statistics.stdev(values)
    low, high = natural_range("exposure_s", horizon, load_scenario(SCENARIOS["coffee_shift"]))  # what desmon estimate takes
    needed = _projected(values, (low, high), args.draws)
    projected = int(statistics.median(needed))
    horizon_needed = int(statistics.median(_projected(values, (0.0, horizon), args.draws)))
    unsized = int(statistics.median(_projected(values, (low, high), args.draws, sized=False)))
    clt = math.ceil((float(norm.ppf(0.995)) * sd / (0.01 * mean)) ** 2)
    floor = math.ceil((high - mean) * math.log(1 / 0.01) / (0.02 * mean))
    minutes = projected / rates["coffee_shift"] / 2
    print(f"coffee_shift +-1 % at 99 %: {projected:,} runs projected on the task's range [{low:,.0f}, {high:,.0f}] (range "
          f"{min(needed):,}..{max(needed):,} over {args.draws} draws), {minutes:.1f} min on 2 cores; on [0, {horizon:,.0f}] "
          f"{horizon_needed:,}; with bets sized for no particular run {unsized:,}; the normal interval would need {clt:,}; "
          f"floor on the task's range {floor:,}")
    times: dict[int, list[float]] = {1: [], 2: []}
    estimates = []
    for workers in [1, 2, 2, 1] * (args.rounds // 2) + [1, 2] * (args.rounds % 2):  # ABBA: a load that drifts weighs on both
        seconds, e = _dask(workers, args.dask_runs, args.dask_until)
        times[workers].append(seconds)
        estimates.append(e.to_json())
    assert all(e == estimates[0] for e in estimates), "1 and 2 workers gave different estimates"
    one, two = statistics.mean(times[1]), statistics.mean(times[2])
    print(f"Dask, {args.dask_runs} runs of {args.dask_until:g} s, {args.rounds} turn(s) each: 1 worker {one:.2f} s "
          f"({', '.join(f'{t:.2f}' for t in times[1])}), 2 workers {two:.2f} s ({', '.join(f'{t:.2f}' for t in times[2])}), "
          f"speed-up {one / two:.2f}x (the same estimate every turn)")
    print(
        f"RESULT robot_day_runs_per_min_core={rates['robot_day']:.2f} coffee_shift_runs_per_min_core={rates['coffee_shift']:.2f} "
        f"runs_needed_1pct_99={projected} runs_needed_horizon_range={horizon_needed} runs_needed_unsized_bets={unsized} clt_runs_needed={clt} floor_runs={floor} "
        f"minutes_2_cores={minutes:.1f} "
        f"speedup={one / two:.2f} one_worker_s={one:.2f} two_workers_s={two:.2f} "
        + " ".join(f"{n}_full_s={f:.3f} {n}_read_s={r:.3f} {n}_read_ratio={f / r:.2f}" for n, (f, r) in against.items())
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
