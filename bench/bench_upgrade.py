"""What the upgrade policy costs: break-before-make against keep-fallback on the fallback day.

``python -m bench.bench_upgrade [--seeds N] [--hours H]`` simulates
``scenarios/fallbacks.py`` (an 8-hour day of coffee deliveries whose detector slots all
have a fallback, with ``torso_pc``'s memory load random-walking between 600 and 900 MB)
for seeds 0..N-1 under both upgrade policies of the corrected deployer:

* ``desmon`` (break-before-make): a running fallback is stopped when only its room keeps
  the preferred detector out, and the preferred detector is started;
* ``desmon-keep-fallback``: the fallback keeps running.

It prints, per policy, the mean and range over the seeds of the unmonitored exposure
(seconds of risky time with no valid detector), the upgrades and their blind time (from
the fallback's stop until the detector that replaced it was ready), switches, false
alarms and slips detected, and per seed the exposure difference (the same seed drives
the same robot, slips and faults under both policies; random start failures and load
walks diverge once the policies' commands differ). Last line: ``RESULT``.
"""

from __future__ import annotations

import argparse
import statistics
from pathlib import Path

from desmon.loader import load_scenario
from desmon.sim.engine import simulate

POLICIES = ("desmon", "desmon-keep-fallback")
#: what keep-fallback breaks by design: it keeps the fallback where an upgrade is due
EXPECTED_BY_KEEP = "preferred-when-possible"
SCENARIO = Path(__file__).resolve().parent.parent / "scenarios" / "fallbacks.py"
KEYS = ("unmonitored_exposure_s", "upgrades", "upgrades_failed", "upgrade_blind_s", "switches", "false_alarms", "slips_detected", "slips_injected")


def _stat(xs: list[float]) -> str:
    return f"{statistics.fmean(xs):9.1f} [{min(xs):g} - {max(xs):g}]"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seeds", type=int, default=5, help="seeds 0..N-1 (default 5)")
    ap.add_argument("--hours", type=float, default=8.0, help="simulated hours per run (default 8)")
    args = ap.parse_args(argv)
    if args.seeds < 1 or not 0 < args.hours < 1e6:
        ap.error("--seeds must be >= 1 and --hours a positive number")
    scenario = load_scenario(SCENARIO)
    runs: dict[str, list[dict[str, float]]] = {p: [] for p in POLICIES}
    for seed in range(args.seeds):
        for policy in POLICIES:
            r = simulate(scenario, policy, seed=seed, until=args.hours * 3600.0)
            m = r.metrics
            # keep-fallback breaks preferred-when-possible by design (it never upgrades); nothing else may break
            bad = sorted({name for _t, name, _m in r.violations} - ({EXPECTED_BY_KEEP} if policy == "desmon-keep-fallback" else set()))
            if bad:
                raise SystemExit(f"seed {seed}, {policy}: invariants violated: {', '.join(bad)}")
            runs[policy].append({k: float(m[k]) for k in KEYS})
            print(f"seed {seed} {policy:<22} exposure {m['unmonitored_exposure_s']:9.1f} s  upgrades {m['upgrades']:3d} "
                  f"(failed {m['upgrades_failed']}, blind {m['upgrade_blind_s']:.1f} s)", flush=True)
    print(f"\n{args.seeds} seeds x {args.hours:g} h of scenarios/fallbacks.py; mean [min - max]")
    for key in KEYS:
        print(f"  {key:<24}" + "".join(f"  {p}: {_stat([r[key] for r in runs[p]])}" for p in POLICIES))
    diff = [a["unmonitored_exposure_s"] - b["unmonitored_exposure_s"] for a, b in zip(*runs.values())]
    print(f"  exposure, break-before-make minus keep-fallback, per seed: {', '.join(f'{d:+.1f}' for d in diff)} s")
    mean = statistics.fmean
    print(
        "RESULT "
        f"seeds={args.seeds} hours={args.hours:g} "
        f"exposure_bbm={mean(r['unmonitored_exposure_s'] for r in runs['desmon']):.1f} "
        f"exposure_keep={mean(r['unmonitored_exposure_s'] for r in runs['desmon-keep-fallback']):.1f} "
        f"exposure_diff_mean={mean(diff):.1f} exposure_diff_min={min(diff):.1f} exposure_diff_max={max(diff):.1f} "
        f"upgrades_per_run={mean(r['upgrades'] for r in runs['desmon']):.1f} "
        f"upgrade_blind_s_per_run={mean(r['upgrade_blind_s'] for r in runs['desmon']):.1f}"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
