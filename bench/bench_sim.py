"""The simulation's speed: the robot-day scenario (``scenarios/robot_day.py``), in process.

What it runs and prints, for one seed (``--seed``, default 0) and one horizon (``--until``,
default the scenario's 8 h day, 28,800 simulated s):

* the day with signals and detectors on, as a user runs it: wall seconds of
  ``SimWorld.run`` (the scenario loaded and the world built beforehand, not counted),
  simulated seconds per wall second (``x_real_time``), the SimPy events it stepped and
  the sensor samples it read. Where desmon forks a worker that renders the tactile frames
  ahead (``render_ahead`` automatic: Linux, 2+ cores, one thread; docs/design.md,
  "Rendering ahead"), it does so here too: the line says so, with the blocks taken from
  it (``ahead_blocks``) and the CPU seconds of this process (``sim_cpu_s``) and of all processes (``cpu_s``);
* the bare SimPy cost of the same event count: one ``env.timeout`` per event on an empty
  ``simpy.Environment``, the fastest of 21 runs (below), and the ratio of the full run's wall time
  to it (``ratio_bare``: a ratio, so it carries over to a slower machine);
* the same day rendered in this process alone (``render_ahead=False``: ``serial_s`` and
  ``serial_ratio_bare``), the same bytes;
* the same day with signals off (``signals_off_s``): the deployment core, the repository,
  the audit of the invariants after every reaction, the infrastructure and SimPy only.

Goals (stated for the 8 h day on an idle 2-core machine): at least 5,000x real time, at
most 100x the bare SimPy cost, signals off under 1.5 s. Each is printed ``met`` or ``NOT
met``; with a shorter ``--until`` (``--quick``: the first half hour) the figures are
printed but not judged.

The last line is ``RESULT x_real_time=<float> ratio_bare=<float> signals_off_s=<float>
wall_s=<float> bare_s=<float> events=<int> until_s=<float> serial_s=<float>
serial_ratio_bare=<float> cpu_s=<float> sim_cpu_s=<float> ahead_blocks=<int>`` (``sim_cpu_s``: the
CPU seconds of the simulation's own process; ``cpu_s`` adds the workers').

The day runs ``--repeat`` times each way (default 3), each in a fresh world, and the
fastest counts. The bare figure is the lowest of six gauges, each the fastest of 21 runs
with the objects that exist beforehand frozen out of the garbage collector's scans (a full
collection over the day's heap during a bare run would be counted as SimPy's cost): three
in this process (before the day, of 25,000 events scaled to the day's count; after the
days as a user runs them; after the one-process and signals-off days) and three in fresh
interpreters (:func:`bare_elsewhere`). On a shared machine a slow spell during one gauge, or a process
whose every bare run is slow, would otherwise make the ratio flatter the day.
docs/findings.md ("Benchmarks" and "Rendering ahead") has the measured figures and where
the day's time goes.

Run: ``python -m bench.bench_sim [--until SECONDS] [--seed S] [--quick] [--repeat N]``.
"""

from __future__ import annotations

import argparse
import gc
import os
import subprocess
import sys
import time
from pathlib import Path

import simpy

from desmon.loader import load_scenario
from desmon.sim.engine import SimWorld

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "scenarios" / "robot_day.py"

#: the goals for the 8 h day
GOAL_X_REAL_TIME = 5000.0
GOAL_RATIO_BARE = 100.0
GOAL_SIGNALS_OFF_S = 1.5
#: simulated seconds of ``--quick``: the first half hour of the day
QUICK_UNTIL = 1800.0
#: events of the bare gauge measured before the day (about the 8 h day's count)
GAUGE_EVENTS = 25_000
#: runs of the day each way (fresh worlds); the fastest counts, as the bare gauge's fastest does
REPEAT = 3


def bare_simpy_s(n_events: int, repeat: int = 21) -> float:
    """Wall seconds of ``n_events`` timeouts on a bare SimPy environment (fastest of
    ``repeat``), with the objects that exist beforehand (a finished day's heap) frozen out
    of the garbage collector's scans: a full collection over them during the bare run would
    be counted as SimPy's cost, and can make the bare figure swing from 0.019 to 0.035 s."""
    gc.collect()
    gc.freeze()
    try:
        return _fastest(n_events, repeat)
    finally:
        gc.unfreeze()


def bare_elsewhere(n_events: int, processes: int = 3) -> float:
    """:func:`bare_simpy_s` of ``n_events`` in ``processes`` fresh interpreters, the fastest: a
    process whose every bare run is slow (its memory laid out worse) would flatter the ratio."""
    code = "import sys; from bench.bench_sim import bare_simpy_s; print(bare_simpy_s(int(sys.argv[1])))"
    best = float("inf")
    for _ in range(processes):
        out = subprocess.run([sys.executable, "-c", code, str(n_events)], cwd=ROOT, capture_output=True, text=True, check=True)
        best = min(best, float(out.stdout))
    return best


def _fastest(n_events: int, repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        env = simpy.Environment()

        def proc(env: simpy.Environment = env):  # type: ignore[no-untyped-def]
            for _ in range(n_events):
                yield env.timeout(0.01)

        env.process(proc())
        t0 = time.perf_counter()
        env.run()
        best = min(best, time.perf_counter() - t0)
    return best


def _timed_run(world: SimWorld, count: bool):  # type: ignore[no-untyped-def]
    """(wall seconds of ``world.run()``, the run's result, the SimPy events stepped if ``count``)."""
    counter = count_events(world.env) if count else [0]
    t0 = time.perf_counter()
    result = world.run()
    return time.perf_counter() - t0, result, counter[0]


def _cpu_s() -> tuple[float, float]:
    """CPU seconds of this process, and of its reaped children (the workers rendering ahead)."""
    t = os.times()
    return t.user + t.system, t.children_user + t.children_system


def _ahead_taken(world: SimWorld) -> int:
    """Blocks the run took from workers rendering ahead (0: it rendered alone)."""
    return world.bank.signals.ahead_taken if world.bank is not None else 0


def count_events(env: simpy.Environment) -> list[int]:
    """A one-item list counting the events ``env`` steps from now on (its ``step`` wrapped)."""
    counter = [0]
    step = env.step

    def counted() -> None:
        counter[0] += 1
        step()

    env.step = counted  # type: ignore[method-assign]
    return counter


def _verdict(ok: bool, judged: bool) -> str:
    if not judged:
        return "not judged (the goals are for the 8 h day)"
    return "met" if ok else "NOT met"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m bench.bench_sim", description=__doc__.split("\n")[0])
    ap.add_argument("--until", type=float, default=None, help="simulated seconds (default: the 8 h day)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--quick", action="store_true", help=f"the first {QUICK_UNTIL:.0f} simulated s only (a smoke run of a few seconds)")
    ap.add_argument("--repeat", type=int, default=REPEAT, help=f"runs of the day each way, the fastest counts (default {REPEAT})")
    ap.add_argument("--collector", action="store_true", help="instead: the collector's cost of many short runs in a process with a large heap")
    a = ap.parse_args(argv)
    if a.collector:
        return collector_bench()
    if a.seed < 0:
        ap.error(f"--seed {a.seed}: give a seed of 0 or more")
    if a.repeat < 1:
        ap.error(f"--repeat {a.repeat}: give at least 1 run")
    until = a.until if a.until is not None else (QUICK_UNTIL if a.quick else None)
    sc = load_scenario(SCENARIO)
    gauge = bare_simpy_s(GAUGE_EVENTS) / GAUGE_EVENTS  # seconds per bare event, before the day
    days = []  # (wall, result, events, CPU s of (this process, the workers), blocks rendered ahead), one per fresh world
    for _ in range(a.repeat):
        world = SimWorld(sc, seed=a.seed, until=until)  # as a user runs it: rendering ahead where desmon does unasked
        own0, kids0 = _cpu_s()
        wall_i, r_i, events_i = _timed_run(world, count=True)
        own1, kids1 = _cpu_s()
        days.append((wall_i, r_i, events_i, (own1 - own0, kids1 - kids0), _ahead_taken(world)))
    wall, r, events, (sim_cpu, kids_cpu), ahead = min(days, key=lambda d: d[0])
    cpu = sim_cpu + kids_cpu
    bare = min(bare_simpy_s(events), gauge * events)
    serial = min(_timed_run(SimWorld(sc, seed=a.seed, until=until, render_ahead=False), count=False)[0] for _ in range(a.repeat))
    off, _r0, _n = _timed_run(SimWorld(sc, seed=a.seed, until=until, signals=False), count=False)
    bare = min(bare, bare_simpy_s(events))  # a third gauge, at the end: a slow spell seldom covers all three
    bare = min(bare, bare_elsewhere(events))  # and in fresh interpreters: a slow process does not count
    sim = r.horizon
    x_real = sim / wall
    ratio = wall / bare
    judged = sim >= 28800
    samples = r.metrics.get("samples", {})
    print(f"robot day, seed {a.seed}: {sim:,.0f} sim-s in {wall:.2f} s wall -> {x_real:,.0f}x real time")
    print(f"  fastest of {a.repeat} runs, each in a fresh world: {', '.join(f'{d[0]:.2f}' for d in days)} s")
    print(f"  SimPy events: {events:,}; samples wrench {samples.get('wrench', 0):,}, tactile {samples.get('tactile', 0):,}")
    how = f"rendered ahead in forked workers ({ahead:,} blocks taken from them)" if ahead else "in this process alone"
    print(f"  {how}; CPU s of all processes: {cpu:.2f} (the simulation's process {sim_cpu:.2f}, the workers {kids_cpu:.2f})")
    print(f"  bare SimPy, same event count: {bare:.4f} s ({events / bare:,.0f} events/s); full run / bare: {ratio:.1f}x")
    print(f"  same day rendered in this process alone (render_ahead=False), fastest of {a.repeat}: {serial:.2f} s wall, {serial / bare:.1f}x bare SimPy")
    print(f"  same day with signals off: {off:.2f} s wall (deployment core, repository, audit, infrastructure, SimPy)")
    print(f"  goal >= {GOAL_X_REAL_TIME:,.0f}x real time: {_verdict(x_real >= GOAL_X_REAL_TIME, judged)}")
    print(f"  goal <= {GOAL_RATIO_BARE:.0f}x bare SimPy: {_verdict(ratio <= GOAL_RATIO_BARE, judged)}")
    print(f"  goal signals off < {GOAL_SIGNALS_OFF_S} s: {_verdict(off < GOAL_SIGNALS_OFF_S, judged)}")
    print(
        f"RESULT x_real_time={x_real:.1f} ratio_bare={ratio:.1f} signals_off_s={off:.3f} "
        f"wall_s={wall:.3f} bare_s={bare:.4f} events={events} until_s={sim:.0f} "
        f"serial_s={serial:.3f} serial_ratio_bare={serial / bare:.1f} cpu_s={cpu:.3f} sim_cpu_s={sim_cpu:.3f} ahead_blocks={ahead}"
    )
    return 0


#: the short runs and the heap (objects built before them) of ``--collector``
COLLECTOR_RUNS, COLLECTOR_HEAP = 20, 3_000_000


def collector_bench() -> int:
    """CPU seconds of :data:`COLLECTOR_RUNS` runs of the coffee handover in this process
    once :data:`COLLECTOR_HEAP` dicts (and as many lists) exist: with desmon's collector
    policy, the runs sharing one Collector and each given none (a caller of one run), and
    with a full collection after every run (the baseline, measured here too)."""
    import desmon.sim.collector as collector
    from desmon.sim.engine import simulate

    sc = load_scenario("scenarios/coffee_handover.py")
    simulate(sc, "desmon", seed=0)  # imports and caches settle
    heap = [{"a": [i]} for i in range(COLLECTOR_HEAP)]
    cpu = {}
    for name, full_after in (("every_run", 0.0), ("policy", collector.FULL_AFTER), ("unshared", None)):
        # the runs' bookkeeping, as a caller of many runs shares it (unshared: each run its own)
        shared = collector.Collector(full_after) if full_after is not None else None
        t0 = time.process_time()
        for seed in range(COLLECTOR_RUNS):
            simulate(sc, "desmon", seed=seed, collector=shared)
        cpu[name] = time.process_time() - t0
    print(f"{COLLECTOR_RUNS} runs of the coffee handover beside {2 * len(heap):,} objects: "
          f"{cpu['policy']:.2f} CPU s sharing a Collector, {cpu['unshared']:.2f} CPU s each with its own, "
          f"{cpu['every_run']:.2f} CPU s with a full collection after each run")
    print(f"RESULT runs={COLLECTOR_RUNS} heap_objects={2 * len(heap)} policy_cpu_s={cpu['policy']:.3f} "
          f"unshared_cpu_s={cpu['unshared']:.3f} every_run_cpu_s={cpu['every_run']:.3f} "
          f"ratio={cpu['every_run'] / max(cpu['policy'], 1e-9):.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
