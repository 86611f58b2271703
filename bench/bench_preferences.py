"""What soft preferences cost the checker, and what leasing an edge server buys the robot.

``python -m bench.bench_preferences [--seeds N] [--hours H] [--quick]`` prints two tables.

1. **Checker cost of preferences.** For every shipped scenario with checker bounds (and
   without preferences of its own), ``desmon verify`` (corrected deployer, auto engine)
   runs twice in the same process: as shipped, and with a preference added to every
   deployment specification (``most_free(memory)``, weight 1, plus ``spread()``, weight
   0.5). The table gives the verdict, the distinct states, the engine that ran and the
   wall time of each, and the time ratio. Preferences only reorder acceptable platforms,
   so they may change which platform a graph lands on, and with it the states reached.
2. **Leasing.** ``scenarios/cloud_offload.py`` is simulated for seeds 0..N-1 with and
   without the lease. The table gives the mean and [min-max] of the unmonitored exposure,
   the errors, the leases and the leased seconds. The same seed drives the same robot,
   slips, loads and requirement changes in both runs; the runs diverge only once a lease
   is requested.

Last line: ``RESULT pref_time_ratio=<median ratio> exposure_with_lease=<mean>
exposure_without_lease=<mean>``.
"""

from __future__ import annotations

import argparse
import statistics
import time
from dataclasses import replace
from pathlib import Path

from desmon.loader import load_scenario
from desmon.model.requirements import Preference
from desmon.model.scenario import Scenario
from desmon.sim.engine import simulate
from desmon.verify.checker import Checker

ROOT = Path(__file__).resolve().parent.parent
SCENARIOS = ROOT / "scenarios"
CLOUD = SCENARIOS / "cloud_offload.py"
ADDED = (Preference("most_free", ("memory",), 1.0), Preference("spread", (), 0.5))


def with_preferences(scenario: Scenario) -> Scenario:
    """``scenario`` with :data:`ADDED` appended to every specification that has memory to score."""
    model = scenario.model
    caps = {r for p in model.platforms for r, _ in p.capacities}
    extra = tuple(x for x in ADDED if x.kind != "most_free" or "memory" in caps)
    specs = tuple(replace(s, requirements=s.requirements + extra) for s in model.specs)
    return replace(scenario, model=replace(model, specs=specs))


def verify(scenario: Scenario, repeat: int = 3) -> tuple[str, int, str, float]:
    """Verdict, states, engine and the best wall time of ``repeat`` runs (the first also warms imports and memos up)."""
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        res = Checker(scenario, "desmon").run(progress=False)
        best = min(best, time.perf_counter() - t0)
    return res.verdict, res.states, getattr(res, "engine", "?"), best


def checker_table(quick: bool) -> list[float]:
    ratios = []
    print(f"{'scenario':<22} {'verdict':<9} {'states':>7} {'s':>7}   {'+prefs verdict':<14} {'states':>7} {'s':>7}  ratio  engine")
    for path in sorted(SCENARIOS.glob("*.py")):
        sc = load_scenario(path)
        if sc.checker is None or path == CLOUD or any(s.preferences for s in sc.model.specs):
            continue
        if quick and path.stem not in ("coffee_handover", "platform_crash"):
            continue
        v0, n0, e0, t0 = verify(sc)
        v1, n1, e1, t1 = verify(with_preferences(sc))
        ratio = t1 / t0 if t0 > 0 else float("nan")
        ratios.append(ratio)
        print(f"{path.stem:<22} {v0:<9} {n0:>7} {t0:>7.2f}   {v1:<14} {n1:>7} {t1:>7.2f}  {ratio:5.2f}  {e0}/{e1}")
    return ratios


def lease_table(seeds: int, hours: float) -> tuple[float, float]:
    rows = {}
    for lease in (True, False):
        sc = load_scenario(CLOUD, params={"lease": str(lease), "hours": str(hours)})
        ms = [simulate(sc, seed=s).metrics for s in range(seeds)]
        rows[lease] = ms
    print()
    print(f"cloud_offload, {hours:g} h, seeds 0..{seeds - 1} (mean [min-max])")
    for lease, ms in rows.items():
        ex = [m["unmonitored_exposure_s"] for m in ms]
        err = [sum(m["errors"].values()) for m in ms]
        print(
            f"  lease={str(lease):<5}  exposure {statistics.fmean(ex):8.1f} s [{min(ex):.1f}-{max(ex):.1f}]"
            f"  errors {statistics.fmean(err):6.1f} [{min(err)}-{max(err)}]"
            f"  leases {statistics.fmean(m['leases'] for m in ms):4.1f}  leased {statistics.fmean(m['leased_s'] for m in ms):8.1f} s"
        )
    diffs = [a["unmonitored_exposure_s"] - b["unmonitored_exposure_s"] for a, b in zip(rows[True], rows[False])]
    print(f"  exposure with - without, per seed: {', '.join(f'{d:+.1f}' for d in diffs)} s")
    mean = lambda ms: statistics.fmean(m["unmonitored_exposure_s"] for m in ms)  # noqa: E731
    return mean(rows[True]), mean(rows[False])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seeds", type=int, default=5, help="seeds 0..N-1 for the lease table (default 5)")
    ap.add_argument("--hours", type=float, default=2.0, help="simulated hours per cloud_offload run (default 2)")
    ap.add_argument("--quick", action="store_true", help="two scenarios, 2 seeds, 0.5 h (a smoke run)")
    args = ap.parse_args(argv)
    seeds, hours = (2, 0.5) if args.quick else (args.seeds, args.hours)
    ratios = checker_table(args.quick)
    with_lease, without = lease_table(seeds, hours)
    med = statistics.median(ratios) if ratios else float("nan")
    print(f"RESULT pref_time_ratio={med:.3f} exposure_with_lease={with_lease:.1f} exposure_without_lease={without:.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
