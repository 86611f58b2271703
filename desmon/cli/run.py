"""``desmon run``: simulate a scenario in the SimPy world and print a readable summary.

Exit codes: 0 every audit passed, 1 an invariant was violated, 2 bad input (raised as a
one-line :class:`~desmon.errors.DesmonError`, printed by the CLI).
"""

from __future__ import annotations

import contextlib
import json
import sys
import time
from typing import IO, Any, Callable, Iterator

from desmon.errors import ScenarioError
from desmon.paths import replacing
from desmon.progress import StatusLine
from desmon.sim.engine import RunResult, SimWorld
from desmon.sim.trace import Trace

__all__ = ["run_command", "format_summary", "summary_json"]

MAX_TIMELINE = 40
#: wall seconds after which a run shows its progress line (a short run shows none)
PROGRESS_AFTER = 1.0
#: how the progress line of a run starts (a fleet run's line too)
PROGRESS_PREFIX = "desmon run: "


def _fmt(v: Any) -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.3f}".rstrip("0").rstrip(".") if v != int(v) else f"{v:g}"
    if isinstance(v, dict):
        return ", ".join(f"{k} {_fmt(x)}" for k, x in v.items()) or "-"
    return str(v)


def format_summary(r: RunResult, wall: float | None = None) -> str:
    m = r.metrics
    lines = [f"{r.scenario.name} -- SimPy world, deployer {r.deployer}, seed {r.seed}, {r.horizon:g} s simulated"]
    if wall is not None:
        lines[0] += f" in {wall:.2f} s wall"
    lines += _signal_status(r)
    lines += ["", "Deployment decisions:"]
    shown = 0
    rows: list[tuple[float, str]] = []
    for d in r.decisions:
        why = f" ({d['why']})" if d.get("why") else ""
        rows.append((d["t"], f"  t={d['t']:>9.3f}s  {d['command']} {d['graph']} on {d['platform']}: {'ok' if d['ok'] else 'FAILED'}{why}"))
    for e in r.errors:
        rows.append((e.time, f"  t={e.time:>9.3f}s  ERROR {e.kind}: {e.graph}" + (f" on {e.platform}" if e.platform else "")))
    rows.sort(key=lambda x: x[0])
    for _t, line in rows:
        if shown >= MAX_TIMELINE:
            lines.append(f"  ... {len(rows) - shown} more (see --trace)")
            break
        lines.append(line)
        shown += 1
    if not rows:
        lines.append("  (none)")
    lines += ["", "Errors by kind:"]
    lines += [f"  {k:<32} {n}" for k, n in m["errors"].items()] or ["  (none)"]
    lines += ["", "Metrics:"]
    order = [
        ("unmonitored exposure (s)", "unmonitored_exposure_s"),
        ("risky time (s)", "risky_time_s"),
        ("switches", "switches"),
        ("blind time per switch (s)", "blind_time_per_switch_s"),
        ("blind time max (s)", "blind_time_max_s"),
        ("starts / failed starts", None),
        ("stops", "stops"),
        ("migrations", "migrations"),
        ("upgrades / failed upgrades", None),
        ("upgrade blind time (s)", "upgrade_blind_s"),
        ("requirement changes", "requirement_changes"),
        ("leases", "leases"),
        ("leased time (s)", "leased_s"),
        ("slips injected", "slips_injected"),
        ("slips detected", "slips_detected"),
        ("slips missed", "slips_missed"),
        ("false alarms", "false_alarms"),
        ("detection latency median (s) [2]", "latency_median_s"),
        ("detection latency p95 (s) [2]", "latency_p95_s"),
        ("memory peak (MB) [1]", "memory_peak_mb"),
        ("over capacity (s) [1]", "overcommit_s"),
        ("reactions / audits", None),
    ]
    for label, key in order:
        if key is None:
            if label.startswith("starts"):
                val = f"{m['starts']} / {m['start_failures']}"
            elif label.startswith("upgrades"):
                val = f"{m['upgrades']} / {m['upgrades_failed']}"
            else:
                val = f"{m['reactions']} / {m.get('audits', '-')}"
        elif key not in m:
            continue
        else:
            val = _fmt(m[key])
        lines.append(f"  {label:<30} {val}")
    lines += [
        "  [1] background load + running detectors. The load is not a deployment: the peak can pass",
        "      the capacity for the instant (0 s) before the deployer reacts to a load rise, and the",
        "      no-overcommit invariant counts deployments only.",
        "  [2] first alarm minus slip-motion onset; an alarm up to 0.3 s before onset counts (the force",
        "      detector fires while the pull builds up, before the object moves), so it can be negative.",
        "",
    ]
    if r.violations:
        lines.append(f"INVARIANTS VIOLATED ({len(r.violations)}):")
        for t, name, msg in r.violations[:10]:
            lines.append(f"  t={t:.3f}s {name}: {msg}")
        if len(r.violations) > 10:
            lines.append(f"  ... {len(r.violations) - 10} more")
    else:
        lines.append("Invariants: all held at every quiescent point (after each reaction with no further stimulus pending).")
    return "\n".join(lines) + "\n"


def _signal_status(r: RunResult) -> list[str]:
    """What the exposure figures mean in this run: signals off, or graphs without a signal model."""
    m = r.metrics
    if not m.get("signals", True):
        why = " (the world is derived from the scripted timeline)" if r.scenario.world is None else ""
        return [
            f"Signals: off{why}: no detector is simulated; a running, warmed-up",
            "  deployment counts as monitoring, and slips are injected but not detected.",
        ]
    missing = m.get("no_signal_model") or {}
    if not missing:
        return []
    graphs = "; ".join(f"{g} (reads {', '.join(kinds)})" for g, kinds in missing.items())
    return [
        f"NO SIGNAL MODEL: {graphs}",
        "  these run and use memory but can never alarm, so they never count as monitoring (their time",
        "  is unmonitored exposure): map the kinds in World(signal_kinds=...) or set World(signals=False).",
    ]


def summary_json(r: RunResult, wall: float | None = None) -> dict[str, Any]:
    return {
        "scenario": r.scenario.name,
        "deployer": r.deployer,
        "seed": r.seed,
        "horizon_s": r.horizon,
        "wall_s": None if wall is None else round(wall, 3),
        "decisions": r.decisions,
        "errors": [e.to_json() for e in r.errors],
        "violations": [{"t": t, "invariant": n, "message": m} for t, n, m in r.violations],
        "metrics": r.metrics,
    }


def run_command(
    args: Any, out: IO[str] | None = None, err: IO[str] | None = None, before_run: Callable[[float], None] | None = None
) -> int:
    """Simulate ``args.scenario``; ``before_run(horizon)`` may refuse the run once the horizon is known."""
    from desmon.loader import load_from_args

    out = out or sys.stdout
    err = err or sys.stderr
    if args.until is not None and not args.until > 0:
        raise ScenarioError(f"--until {args.until!r}: give a positive number of simulated seconds")
    if args.seed is not None and args.seed < 0:
        raise ScenarioError(f"--seed {args.seed!r}: give a non-negative integer")
    scenario = load_from_args(args)
    from desmon.sim.fleet import is_fleet

    show = not getattr(args, "no_progress", False) and not args.json
    if is_fleet(scenario):  # a fleet of robots sharing edge servers: desmon.sim.fleet
        return _run_fleet(args, scenario, out, err, show)
    from desmon.sim.world import world_of

    horizon = float(world_of(scenario).horizon)  # declared, or derived from the timeline
    if args.until is not None and args.until > horizon:
        raise ScenarioError(
            f"--until {args.until:g}: the scenario's task ends at its horizon of {horizon:g} s; "
            "give --until at most that (past it the last action would go on forever)"
        )
    if before_run is not None:
        before_run(float(args.until) if args.until is not None else horizon)
    t_wall = time.perf_counter()
    with contextlib.ExitStack() as stack:
        line = stack.enter_context(_status_line(err))  # ended before the summary, or before an error's message
        progress = _reporter(line, t_wall) if show else None
        # the trace replaces an existing file only once the run is complete (nothing lost on an error)
        fh = stack.enter_context(replacing(args.trace)) if args.trace else None
        world = SimWorld(
            scenario, deployer=args.deployer, seed=args.seed or 0, until=args.until, trace=Trace(fh, keep=False), progress=progress
        )
        result = world.run()
        result.metrics["audits"] = world.audits
    wall = time.perf_counter() - t_wall
    if args.json:
        out.write(json.dumps(summary_json(result, wall), indent=2) + "\n")
    else:
        out.write(format_summary(result, wall))
        if args.trace and not getattr(args, "trace_is_temporary", False):
            out.write(f"Trace: {args.trace} ({result.trace.count} records)\n")
    return 1 if result.violations else 0


def _run_fleet(args: Any, scenario: Any, out: IO[str], err: IO[str], show: bool) -> int:
    """``desmon run`` on a fleet scenario (:mod:`desmon.sim.fleet`), its progress on one line."""
    from desmon.sim.fleet import run_fleet_command, write_fleet_report

    with _status_line(err) as line:  # ended before the summary, or before an error's message
        result = run_fleet_command(args, scenario, _reporter(line, time.perf_counter()) if show else None)
    return write_fleet_report(args, result, out)


@contextlib.contextmanager
def _status_line(err: IO[str]) -> Iterator[StatusLine]:
    """A :class:`StatusLine` on ``err``, ended however the block ends."""
    line = StatusLine(err)
    try:
        yield line
    finally:
        line.close()


def _reporter(line: StatusLine, t_wall: float) -> Callable[[float, float], None]:
    """The progress callback of a run (one robot or a fleet): drawn on ``line`` once the
    run has taken :data:`PROGRESS_AFTER` wall seconds."""

    def report_progress(now: float, end: float) -> None:
        if time.perf_counter() - t_wall > PROGRESS_AFTER:
            line.show(f"{PROGRESS_PREFIX}{100 * now / end:5.1f}%  t={now:.0f}/{end:.0f} s")

    return report_progress
