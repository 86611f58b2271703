"""How far the interval ``desmon run`` prints under a fleet's mean exposure per robot can be trusted.

``python -m bench.fleet_interval [--robots N] [--edges M] [--hours H] [--seeds K] [--quick]``
runs ``scenarios/fleet.py`` with those parameters for seeds ``0 .. K-1``. Each run's summary
gives the mean unmonitored exposure per robot a 95 % interval over its robots: the normal
approximation (``desmon.stats.mean_interval``), since the robots are not the independent,
alike runs the betting interval's guarantee needs (they share the edge servers, their idle
times differ). Over the seeds this bench compares:

* the seeds' spread of the fleet's mean (its standard deviation over the ``K`` seeds) with
  the standard error each run reads off its robots (``s / sqrt(N)``, averaged over the runs):
  the interval is as wide as it should be when the two agree;
* how many of the ``K`` intervals hold the mean of all ``K`` seeds' means (the best stand-in
  for the fleet's expected mean per robot), for the normal interval and, beside it, for the
  betting interval over the robots in ``[0, horizon]`` (and their mean half-widths).

Last line: ``RESULT seeds=K seed_sd_s=... robot_se_s=... normal_held=... normal_half_width_s=...
betting_held=... betting_half_width_s=...``. ``--quick``: 4 robots, 2 edge servers, 0.25 h, 3 seeds.
"""

from __future__ import annotations

import argparse
import math
import statistics
from pathlib import Path

from desmon.errors import DesmonError
from desmon.loader import load_scenario
from desmon.sim.fleet import simulate_fleet
from desmon.stats import mean_interval

SCENARIO = Path(__file__).resolve().parent.parent / "scenarios" / "fleet.py"
CONFIDENCE = 0.95


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(prog="python -m bench.fleet_interval", description=__doc__.splitlines()[0])
    ap.add_argument("--robots", type=int, default=20)
    ap.add_argument("--edges", type=int, default=2)
    ap.add_argument("--hours", type=float, default=1.0)
    ap.add_argument("--seeds", type=int, default=30)
    ap.add_argument("--quick", action="store_true", help="4 robots, 2 edge servers, 0.25 h, 3 seeds")
    args = ap.parse_args(argv)
    if args.quick:
        args.robots, args.edges, args.hours, args.seeds = 4, 2, 0.25, 3
    if args.robots < 2 or args.seeds < 2:
        ap.error("give --robots 2 or more and --seeds 2 or more: an interval over the robots, a spread over the seeds")
    if args.edges < 1 or not (math.isfinite(args.hours) and args.hours > 0):
        ap.error(f"--edges {args.edges} / --hours {args.hours}: give 1 or more edge servers and a positive number of hours")
    try:
        scenario = load_scenario(str(SCENARIO), {"robots": str(args.robots), "edges": str(args.edges), "hours": str(args.hours)})
    except DesmonError as exc:  # (what the fleet scenario refuses: its limits are its own)
        ap.error(str(exc))
    delta = 1.0 - CONFIDENCE
    runs = []
    for seed in range(args.seeds):
        result = simulate_fleet(scenario, seed=seed)
        values = [m["unmonitored_exposure_s"] for m in result.robots.values()]
        runs.append((values, mean_interval(values, delta), mean_interval(values, delta, (0.0, result.horizon))))
        print(f"seed {seed}: mean {statistics.fmean(values):.1f} s over {len(values)} robots, normal [{runs[-1][1].low:.1f}, "
              f"{runs[-1][1].high:.1f}], betting [{runs[-1][2].low:.1f}, {runs[-1][2].high:.1f}]", flush=True)
    means = [statistics.fmean(v) for v, _, _ in runs]
    grand = statistics.fmean(means)
    seed_sd = statistics.stdev(means)
    robot_se = statistics.fmean(statistics.stdev(v) / math.sqrt(len(v)) for v, _, _ in runs)
    held = [sum(iv.low <= grand <= iv.high for iv in ivs) for ivs in ([n for _, n, _ in runs], [b for _, _, b in runs])]
    half = [statistics.fmean(iv.half_width for iv in ivs) for ivs in ([n for _, n, _ in runs], [b for _, _, b in runs])]
    print(f"{args.robots} robots, {args.edges} edge servers, {args.hours:g} h, seeds 0..{args.seeds - 1}: the fleet's mean "
          f"exposure per robot {grand:.1f} s on average; its sd over the seeds {seed_sd:.1f} s, the standard error over the "
          f"robots {robot_se:.1f} s on average")
    print(f"intervals holding the seeds' mean: normal {held[0]}/{args.seeds} (half-width {half[0]:.1f} s), "
          f"betting {held[1]}/{args.seeds} (half-width {half[1]:.1f} s)")
    print(f"RESULT seeds={args.seeds} seed_sd_s={seed_sd:.2f} robot_se_s={robot_se:.2f} normal_held={held[0]} "
          f"normal_half_width_s={half[0]:.2f} betting_held={held[1]} betting_half_width_s={half[1]:.2f}")


if __name__ == "__main__":
    main()
