"""The table engine on preferences, rebalancing, requirement changes and joining platforms.

``python -m bench.bench_table_prefs [--repeat N] [--quick]`` runs ``desmon verify``'s
search (corrected deployer) with ``engine="direct"`` and ``engine="table"``, alternating,
best of N wall times each, on

* ``scenarios/cloud_offload.py`` as shipped (preferences, rebalance, an on-demand edge
  server that joins and leaves, two requirement changes: 129 states);
* ``cloud_offload`` with wider bounds: torso load in 100 MB steps from 400 to 900 MB, arm
  load from 100 to 300 MB, the wrench and a tactile pad failing (two failures at a time)
  and one failing start per reaction;
* every other shipped scenario with checker bounds, with a ``most_free(memory)`` (weight
  1) and a ``spread()`` (weight 0.5) preference added to every specification (as
  ``bench.bench_preferences`` adds them).

Both engines must give the same verdict, states and transitions (checked). The figure is
the ratio direct / table of the wall times (above 1: the table engine is faster).

Last line: ``RESULT cloud_ratio=<shipped> cloud_wide_ratio=<wider> pref_median_ratio=<median over the others>``.
"""

from __future__ import annotations

import argparse
import statistics
import time
from dataclasses import replace
from pathlib import Path

from bench.bench_preferences import with_preferences
from desmon.loader import load_scenario
from desmon.model.scenario import Scenario
from desmon.verify.bounds import levels
from desmon.verify.checker import Checker

ROOT = Path(__file__).resolve().parent.parent
SCENARIOS = ROOT / "scenarios"


def wide_cloud() -> Scenario:
    """cloud_offload with wider bounds (see the module doc)."""
    s = load_scenario(SCENARIOS / "cloud_offload.py")
    b = replace(
        s.checker, loads={"torso_pc": levels(400, 900, 100), "arm_pc": levels(100, 300, 100)},
        devices=("lwr_wrench", "pad_thumb_prox"), max_failures=2, start_failures=1,
    )
    return replace(s, checker=b)


def timed(scenario: Scenario, repeat: int) -> tuple[tuple, float, float]:
    """(verdict, states, transitions), best direct and best table wall time, alternating."""
    best = {"direct": float("inf"), "table": float("inf")}
    seen = {}
    for _ in range(repeat):
        for engine in ("direct", "table"):
            t0 = time.perf_counter()
            r = Checker(scenario, "desmon").run(engine=engine, progress=False)
            best[engine] = min(best[engine], time.perf_counter() - t0)
            seen[engine] = (r.verdict, r.states, r.transitions)
            assert r.engine == engine
    if seen["direct"] != seen["table"]:
        raise SystemExit(f"{scenario.name}: the engines disagree: {seen}")
    return seen["table"], best["direct"], best["table"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=3, help="runs per engine and model (best time kept)")
    ap.add_argument("--quick", action="store_true", help="cloud_offload and two other scenarios only")
    args = ap.parse_args()
    rows = [("cloud_offload", load_scenario(SCENARIOS / "cloud_offload.py")), ("cloud_offload wide", wide_cloud())]
    for path in sorted(SCENARIOS.glob("*.py")):
        if path.stem == "cloud_offload" or (args.quick and path.stem not in ("coffee_handover", "robot_day")):
            continue
        s = load_scenario(path)
        if s.checker is None or any(spec.preferences for spec in s.model.specs):
            continue
        rows.append((f"{path.stem} +prefs", with_preferences(s)))
    print(f"{'model':28} {'verdict':9} {'states':>9} {'transitions':>12} {'direct s':>9} {'table s':>9} {'direct/table':>12}")
    ratios: dict[str, float] = {}
    for name, scenario in rows:
        (verdict, states, transitions), d, t = timed(scenario, args.repeat)
        ratios[name] = d / t
        print(f"{name:28} {verdict:9} {states:>9,} {transitions:>12,} {d:>9.3f} {t:>9.3f} {d / t:>12.2f}")
    others = [v for k, v in ratios.items() if not k.startswith("cloud_offload")]
    print(
        f"RESULT cloud_ratio={ratios['cloud_offload']:.2f} cloud_wide_ratio={ratios['cloud_offload wide']:.2f} "
        f"pref_median_ratio={statistics.median(others) if others else float('nan'):.2f}"
    )


if __name__ == "__main__":
    main()
