"""The table engine at scale: ``scenarios/scale_family.py`` for growing N, each in its own process.

``python -m bench.bench_scale [--min-platforms N] [--max-platforms N] [--time-limit S] [--engine E]``
checks the family's model with N = ``--min-platforms`` (2), 3, ... platforms, one fresh
process per N (so that each search's resident memory is its own), and prints per N the
states, transitions, seconds, states/s and bytes/state (what ``desmon verify --stats``
prints: the resident memory the search added, over its states). It stops after
``--max-platforms`` or where the next N would not fit in what is left of ``--time-limit``
seconds (estimated from the growth of the last two N: its states times the last
seconds per state); a search that the time limit cuts is reported as incomplete.

The last line ``RESULT platforms=<largest N searched completely> states=... transitions=...
seconds=... cpu_seconds=... states_per_s=... bytes_per_state=... growth=<states of N over N-1>``
carries that N's figures (CPU seconds beside the wall-clock ones: on a shared machine
the search waits for a core). Figures and their discussion: docs/findings.md ("The checker at scale").
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

SCENARIO = Path(__file__).resolve().parents[1] / "scenarios" / "scale_family.py"


def one(platforms: int, engine: str, timeout: float | None) -> dict[str, object]:
    """Check the family's model with ``platforms`` platforms in this process."""
    from desmon.loader import load_scenario
    from desmon.verify.checker import Checker

    scenario = load_scenario(SCENARIO, {"platforms": str(platforms)})
    cpu0 = time.process_time()
    res = Checker(scenario, "desmon").run(engine=engine, max_states=None, timeout=timeout)
    cpu = time.process_time() - cpu0
    return {
        "platforms": platforms, "verdict": res.verdict, "incomplete": res.incomplete, "states": res.states, "transitions": res.transitions,
        "seconds": round(res.seconds, 3), "cpu_seconds": round(cpu, 3), "bytes_per_state": round(res.bytes_per_state, 1), "peak_mb": round(res.peak_mb, 1), "engine": res.engine,
    }


def _child(platforms: int, engine: str, timeout: float) -> dict[str, object]:
    cmd = [sys.executable, "-m", "bench.bench_scale", "--one", str(platforms), "--engine", engine, "--time-limit", f"{timeout:.1f}"]
    proc = subprocess.run(cmd, capture_output=True, text=True, cwd=Path(__file__).resolve().parents[1])
    if proc.returncode:
        raise SystemExit(f"bench_scale: N={platforms} failed (exit {proc.returncode}): {proc.stderr.strip()[-400:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--min-platforms", type=int, default=2, help="the smallest N (2 to 12)")
    ap.add_argument("--max-platforms", type=int, default=6, help="the largest N (2 to 12)")
    ap.add_argument("--time-limit", type=float, default=1800.0, help="seconds for the whole run")
    ap.add_argument("--engine", choices=("table", "direct"), default="table", help="the checker engine")
    ap.add_argument("--one", type=int, help=argparse.SUPPRESS)  # a child: one N, its figures as JSON
    args = ap.parse_args(argv)
    if not 2 <= args.min_platforms <= args.max_platforms <= 12:
        ap.error(f"--min-platforms {args.min_platforms} / --max-platforms {args.max_platforms}: give 2 <= min <= max <= 12")
    if not args.time_limit > 0:
        ap.error(f"--time-limit {args.time_limit}: give a positive number of seconds")
    if args.one is not None:
        print(json.dumps(one(args.one, args.engine, args.time_limit)))
        return 0
    t0 = time.perf_counter()
    rows: list[dict] = []
    print(f"scale family ({SCENARIO.name}), engine {args.engine}, time limit {args.time_limit:g} s")
    print(f"  {'N':>2} {'states':>13} {'transitions':>15} {'seconds':>9} {'CPU s':>9} {'states/s':>10} {'B/state':>8}  verdict", flush=True)
    for n in range(args.min_platforms, args.max_platforms + 1):
        left = args.time_limit - (time.perf_counter() - t0)
        if len(rows) >= 2 and rows[-1]["verdict"] != "INCOMPLETE":
            growth = rows[-1]["states"] / max(rows[-2]["states"], 1)
            estimate = rows[-1]["seconds"] * growth * 1.2  # (seconds per state grow a little with N)
            if estimate > left:
                print(f"  N={n}: about {rows[-1]['states'] * growth:,.0f} states, {estimate:,.0f} s estimated: more than the {left:,.0f} s left")
                break
        if left <= 1 or (rows and rows[-1]["verdict"] == "INCOMPLETE"):
            break
        r = _child(n, args.engine, left)
        rows.append(r)
        rate = r["states"] / r["seconds"] if r["seconds"] else 0.0
        why = f" ({r['incomplete']})" if r["incomplete"] else ""
        print(f"  {n:>2} {r['states']:>13,} {r['transitions']:>15,} {r['seconds']:>9.2f} {r['cpu_seconds']:>9.2f} {rate:>10,.0f} {r['bytes_per_state']:>8.1f}  {r['verdict']}{why}", flush=True)
    done = [r for r in rows if r["verdict"] != "INCOMPLETE"]
    if not done:
        raise SystemExit("bench_scale: no N was searched completely within the time limit")
    last = done[-1]
    growth = last["states"] / done[-2]["states"] if len(done) >= 2 else 0.0
    result = {
        "platforms": last["platforms"], "states": last["states"], "transitions": last["transitions"], "seconds": last["seconds"], "cpu_seconds": last["cpu_seconds"],
        "states_per_s": round(last["states"] / last["seconds"]) if last["seconds"] else 0, "bytes_per_state": last["bytes_per_state"],
        "growth": round(growth, 2),
    }
    print("RESULT " + " ".join(f"{k}={v}" for k, v in result.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
