"""Fleet throughput: N robots sharing M edge servers in one SimPy world.

``python -m bench.bench_fleet [--robots N] [--edges M] [--hours H] [--seed S]`` loads
``scenarios/fleet.py`` with those parameters and runs the fleet world
(:mod:`desmon.sim.fleet`) once. The baseline, measured in the same run first, is the
fleet's first robot alone: its own Scenario in the one-robot world
(:class:`desmon.sim.engine.SimWorld`, signals off, the same hours) -- so the ratio
``fleet wall / (N x one robot's wall)`` is what sharing one environment, one
repository and the edge servers costs per robot (1.0: nothing).

Printed: wall time, simulated seconds per wall second (the ratio to real time),
reactions and repository changes per wall second, the process's peak resident memory
(getrusage maxrss: the fleet's repository, change log and every robot's records; the
interpreter and imports included), the SimPy events the fleet stepped and the bare SimPy
cost of as many events (``bench_sim``'s gauge: one ``env.timeout`` per event on an empty
environment, fastest of 5 after the run, or fastest of 21 of 25,000 events before it, scaled,
if lower), and a last line ``RESULT seconds=<s> realtime_ratio=<x>
peak_mb=<m> ... ratio_bare=<fleet wall / bare>``.

The fleet's goal (100 robots for 8 h in under 60 s) is stated in seconds of one machine;
wall seconds differ between machines by more than the code's changes do (one version of
the code took 46.7 s on one machine and 128-146 s of CPU on another, docs/fleet.md), so ``ratio_bare``, a
ratio to a cost measured in the same run, is the figure to compare across machines.
"""

from __future__ import annotations

import argparse
import gc
import time
from pathlib import Path

from bench.bench_sim import GAUGE_EVENTS, bare_simpy_s, count_events
from desmon.loader import load_scenario
from desmon.sim.engine import SimWorld
from desmon.sim.fleet import FleetWorld, peak_rss_mb, robot_seed

SCENARIO = Path(__file__).resolve().parent.parent / "scenarios" / "fleet.py"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m bench.bench_fleet", description=__doc__.splitlines()[0])
    ap.add_argument("--robots", type=int, default=100)
    ap.add_argument("--edges", type=int, default=20)
    ap.add_argument("--hours", type=float, default=8.0)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    if args.robots < 1 or args.edges < 0 or not args.hours > 0 or args.seed < 0:
        ap.error("give --robots >= 1, --edges >= 0, --hours > 0 and --seed >= 0")
    t = time.perf_counter()
    scenario = load_scenario(SCENARIO, {"robots": str(args.robots), "edges": str(args.edges), "hours": str(args.hours)})
    load_s = time.perf_counter() - t
    horizon = args.hours * 3600.0
    print(f"fleet: {args.robots} robots, {args.edges} edge servers, {horizon:g} s simulated (scenario built in {load_s:.2f} s)")

    # baseline: the first robot alone in the one-robot world
    first = scenario.world.robots[0]
    gc.collect()
    t = time.perf_counter()
    alone = SimWorld(first, seed=robot_seed(args.seed, first.model.robot), signals=False).run()
    base_s = time.perf_counter() - t
    print(f"  one robot alone        {base_s:8.2f} s   {alone.metrics['reactions']:>9,} reactions   {horizon / base_s:10.0f}x real time")

    gauge = bare_simpy_s(GAUGE_EVENTS) / GAUGE_EVENTS  # seconds per bare event, before the fleet (as bench_sim)
    gc.collect()
    world = FleetWorld(scenario, seed=args.seed)
    events = count_events(world.env)
    t = time.perf_counter()
    r = world.run()
    wall = time.perf_counter() - t
    bare = min(bare_simpy_s(events[0], repeat=5), gauge * events[0])
    m = r.metrics
    per_robot = wall / (args.robots * base_s)
    print(
        f"  fleet                  {wall:8.2f} s   {m['reactions']:>9,} reactions   {horizon / wall:10.0f}x real time"
        f"   ({m['reactions'] / wall:,.0f} reactions/s, {m['repository_changes'] / wall:,.0f} repository changes/s)"
    )
    print(f"  fleet / (robots x one robot alone) = {per_robot:.2f}")
    print(f"  SimPy events {events[0]:,}; bare SimPy, same event count: {bare:.3f} s; fleet / bare = {wall / bare:.0f}x")
    print(
        f"  exposure per robot {m['exposure_per_robot_s']['mean']:.1f} s [{m['exposure_per_robot_s']['min']:.1f}-"
        f"{m['exposure_per_robot_s']['max']:.1f}], violations {m['violations']}, errors {m['errors']}"
    )
    peak = peak_rss_mb()
    print(f"  peak memory (max RSS)  {peak:.0f} MB")
    print(
        f"RESULT seconds={wall:.2f} realtime_ratio={horizon / wall:.1f} peak_mb={peak:.0f} robots={args.robots} "
        f"edges={args.edges} hours={args.hours:g} per_robot_vs_alone={per_robot:.2f} "
        f"reactions_per_s={m['reactions'] / wall:.0f} violations={m['violations']} events={events[0]} bare_s={bare:.4f} "
        f"ratio_bare={wall / bare:.0f}"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
