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

``python -m bench.bench_scale --breakdown N`` instead times the parts of one table-engine
search of N platforms: the decision-tree walks (with, inside them, the recorded runs of
the real core), the seen-set lookups and the enabled events, each a pass over a batch
that could in principle be split between processes, and the rest (numbering the new
states in BFS order, counting, the level loop), which could not. Its RESULT line
``platforms=... seconds=... walk_s=... recording_s=... seen_s=... events_s=...
serial_share=... two_workers_bound=...`` ends with Amdahl's bound on the speedup of 2
workers that split every splittable pass perfectly, the recorded runs counted as serial
(each process would need every run its trees lack): docs/design.md quotes it.
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


class _Timed:
    """Wall seconds spent in some methods (outermost calls only), while in a ``with`` block."""

    def __init__(self, where: dict[str, tuple[type, str]]) -> None:
        self.where, self.seconds, self._saved, self._depth = where, dict.fromkeys(where, 0.0), [], 0

    def __enter__(self) -> "_Timed":
        for label, (cls, name) in self.where.items():
            own = getattr(cls, name)
            self._saved.append((cls, name, own if name in vars(cls) else None))  # (None: inherited, deleted again)
            setattr(cls, name, self._timed(label, own))
        return self

    def _timed(self, label: str, own):  # type: ignore[no-untyped-def]
        def timed(*args, **kw):  # type: ignore[no-untyped-def]
            if self._depth:
                return own(*args, **kw)
            self._depth += 1
            t0 = time.perf_counter()
            try:
                return own(*args, **kw)
            finally:
                self.seconds[label] += time.perf_counter() - t0
                self._depth -= 1
        return timed

    def __exit__(self, *exc: object) -> None:
        for cls, name, own in self._saved:
            if own is None:
                delattr(cls, name)
            else:
                setattr(cls, name, own)


def breakdown(platforms: int) -> dict[str, object]:
    """The parts of one table-engine search of the family with ``platforms`` platforms (module docstring)."""
    from desmon.loader import load_scenario
    from desmon.verify.arrays import CodeSet
    from desmon.verify.checker import Checker
    from desmon.verify.table.encoding import Events
    from desmon.verify.table.recording import Recorder
    from desmon.verify.table.tree import DecisionTrees

    scenario = load_scenario(SCENARIO, {"platforms": str(platforms)})
    parts = {"walk": (DecisionTrees, "walk"), "seen": (CodeSet, "contains"), "events": (Events, "enabled")}
    with _Timed(parts) as outer:
        with _Timed({"recording": (Recorder, "record_reaction"), "recording_inv": (Recorder, "record_invariants")}) as runs:
            t0 = time.perf_counter()
            res = Checker(scenario, "desmon").run(engine="table", max_states=None)
            total = time.perf_counter() - t0
    recording = runs.seconds["recording"] + runs.seconds["recording_inv"]
    split = outer.seconds["walk"] - recording + outer.seconds["seen"] + outer.seconds["events"]
    serial = max(total - split, 0.0) / total
    return {
        "platforms": platforms, "states": res.states, "seconds": round(total, 2), "walk_s": round(outer.seconds["walk"], 2),
        "recording_s": round(recording, 2), "seen_s": round(outer.seconds["seen"], 2), "events_s": round(outer.seconds["events"], 2),
        "serial_share": round(serial, 3), "two_workers_bound": round(1.0 / (serial + (1.0 - serial) / 2), 2),
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
    ap.add_argument("--breakdown", type=int, metavar="N", help="time the parts of one table-engine search of N platforms (2 to 12) instead")
    args = ap.parse_args(argv)
    if not 2 <= args.min_platforms <= args.max_platforms <= 12:
        ap.error(f"--min-platforms {args.min_platforms} / --max-platforms {args.max_platforms}: give 2 <= min <= max <= 12")
    if not args.time_limit > 0:
        ap.error(f"--time-limit {args.time_limit}: give a positive number of seconds")
    if args.breakdown is not None:
        if not 2 <= args.breakdown <= 12:
            ap.error(f"--breakdown {args.breakdown}: give a number of platforms from 2 to 12")
        b = breakdown(args.breakdown)
        print(f"scale family ({SCENARIO.name}), N={b['platforms']}: {b['states']:,} states in {b['seconds']} s on the table engine")
        print(f"  tree walks {b['walk_s']} s (of which recorded runs of the real core {b['recording_s']} s), seen-set lookups {b['seen_s']} s, "
              f"enabled events {b['events_s']} s; the rest, and the recorded runs, serial: {100 * b['serial_share']:.0f} %")
        print(f"  2 workers splitting every other pass perfectly: at most {b['two_workers_bound']}x (Amdahl)")
        del b["states"]
        print("RESULT " + " ".join(f"{k}={v}" for k, v in b.items()))
        return 0
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
