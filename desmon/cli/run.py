"""``desmon run``: simulate a scenario in the SimPy world (one robot, or a fleet of robots
sharing edge servers) and print a readable summary, or ``--json``; ``--plot`` draws the run's timeline.

Exit codes: 0 every audit passed, 1 an invariant was violated, 2 bad input (raised as a
one-line :class:`~desmon.errors.DesmonError`, printed by the CLI).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import sys
import tempfile
import time
from typing import IO, TYPE_CHECKING, Any, Callable, Iterator

from desmon.cli.common import EXIT_OK, EXIT_VIOLATED, Subparsers, deployer_arg, draw_trace, load_scenario_of, scenario_arg, warn_uncovered, run_of, world_given
from desmon.cli.options import add_output, add_window, non_negative_int, positive_int, positive_seconds
from desmon.errors import ScenarioError
from desmon.model.checks import exact
from desmon.paths import replacing
from desmon.progress import StatusLine

if TYPE_CHECKING:
    from desmon.model.scenario import Scenario
    from desmon.sim.engine import RunResult
    from desmon.sim.fleet import FleetResult

__all__ = ["add_parser", "run", "run_command", "format_summary", "summary_json", "format_fleet_summary", "fleet_json"]

MAX_TIMELINE = 40
#: wall seconds after which a run shows its progress line (a short run shows none)
PROGRESS_AFTER = 1.0
#: how the progress line of a run starts (a fleet run's line too)
PROGRESS_PREFIX = "desmon run: "
RUN_WINDOW = ("--plot-from", "--plot-to")


def add_parser(sub: Subparsers) -> None:
    p = sub.add_parser("run", help="simulate a scenario in the SimPy world")
    scenario_arg(p)
    p.add_argument("--seed", type=non_negative_int, default=0, help="random seed of the world (faults, slips, start failures)")
    p.add_argument("--until", type=positive_seconds, default=None, help="simulated seconds (default: the scenario's horizon)")
    deployer_arg(p)
    add_output(p, "--trace", suffixes=(".jsonl",), default=None, metavar="FILE.jsonl", help="write the JSON Lines trace to this file")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.add_argument("--no-progress", action="store_true")
    p.add_argument(
        "--timing", choices=("fixed", "exponential"), default=None,
        help="exponential: the Markov world desmon analyze solves (random step durations and delays with the given means)",
    )
    p.add_argument("--phases", type=positive_int, default=None, help="Erlang phases of a task step under --timing exponential (default 1)")
    p.add_argument("--no-signals", action="store_true", help="simulate no sensor signals (exposure counts running, ready detectors)")
    p.add_argument(
        "--render-ahead", choices=("auto", "on", "off"), default="auto",
        help="render the tactile frames and the wrench in forked workers while the run goes on; the output is the same "
        "either way (auto: on Linux with 2+ cores for runs with 20 min or more of object in hand)",
    )
    add_output(
        p, "--plot", suffixes=(".png",), default=None, metavar="FILE.png",
        help="draw the timeline of the run to this PNG (needs desmon[plot])",
    )
    add_window(p, ("--plot-from", "plot_from"), ("--plot-to", "plot_to"), needs=("plot", "--plot"))
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """``desmon run``; with ``--plot`` and no ``--trace`` the trace goes to a temporary file."""
    from desmon.viz.timeline import check_window

    def window_fits(horizon: float) -> None:  # before simulating, once the horizon is known
        check_window(args.plot_from, args.plot_to, horizon, flags=RUN_WINDOW)

    tmp = None
    if args.plot and not args.trace:
        fd, tmp = tempfile.mkstemp(suffix=".jsonl")
        os.close(fd)
        args.trace = tmp
        args.trace_is_temporary = True  # deleted below: the summary does not name it
    try:
        code = run_command(args, before_run=window_fits if args.plot else None)
        if args.plot and code in (EXIT_OK, EXIT_VIOLATED):
            draw_trace(args.trace, args.plot, args.plot_from, args.plot_to, RUN_WINDOW)
        return code
    finally:
        if tmp is not None and os.path.exists(tmp):
            os.unlink(tmp)


def run_command(
    args: Any, out: IO[str] | None = None, err: IO[str] | None = None, before_run: Callable[[float], None] | None = None
) -> int:
    """Simulate ``args.scenario``; ``before_run(horizon)`` may refuse the run once the horizon is known."""
    out = out or sys.stdout
    err = err or sys.stderr
    if args.until is not None and not args.until > 0:
        raise ScenarioError(f"--until {args.until!r}: give a positive number of simulated seconds")
    if args.seed is not None and args.seed < 0:
        raise ScenarioError(f"--seed {args.seed!r}: give a non-negative integer")
    scenario = with_timing(load_scenario_of(args), args)
    from desmon.sim.fleet import is_fleet

    show = not getattr(args, "no_progress", False) and not args.json
    if is_fleet(scenario):  # a fleet of robots sharing edge servers: desmon.sim.fleet
        return _run_fleet(args, scenario, out, err, show)
    from desmon.sim.world import world_of

    world = world_of(scenario)
    horizon = float(world.horizon)  # declared, or derived from the timeline
    if getattr(args, "render_ahead", "auto") == "on" and not world.signals:
        raise ScenarioError(f"--render-ahead on renders sensor signals, and {scenario.name!r} runs without them (--no-signals or its world): drop --render-ahead")
    if args.until is not None and args.until > horizon:
        raise ScenarioError(
            f"--until {exact(args.until)}: the scenario's task ends at its horizon of {exact(horizon)} s; "
            "give --until at most that (past it the last action would go on forever)"
        )
    if before_run is not None:
        before_run(float(args.until) if args.until is not None else horizon)
    t_wall = time.perf_counter()
    result = _simulate(args, scenario, err, show, t_wall)
    wall = time.perf_counter() - t_wall
    if args.json:
        out.write(json.dumps(summary_json(result, wall, world_given(args)), indent=2) + "\n")
    else:
        out.write(format_summary(result, wall))
        if args.trace and not getattr(args, "trace_is_temporary", False):
            out.write(f"Trace: {args.trace} ({result.trace.count} records)\n")
    warn_uncovered(scenario, float(args.until) if args.until is not None else None)  # stderr, JSON or not
    return 1 if result.violations else 0


def with_timing(scenario: Scenario, args: Any) -> Scenario:
    """``scenario`` with the world's timing, phases and signals of ``--timing``,
    ``--phases`` and ``--no-signals`` (unchanged when none is given)."""
    timing, phases, no_signals = getattr(args, "timing", None), getattr(args, "phases", None), getattr(args, "no_signals", False)
    if timing is None and phases is None and not no_signals:
        return scenario
    from dataclasses import replace

    from desmon.sim.fleet import is_fleet
    from desmon.sim.world import world_of

    if is_fleet(scenario):
        given = [f for f, v in (("--timing", timing), ("--phases", phases), ("--no-signals", no_signals)) if v]
        raise ScenarioError(
            f"{' and '.join(given)} {'sets' if len(given) == 1 else 'set'} one robot's World; {scenario.name!r} is a fleet, each robot with a World of its own: "
            f"drop {' and '.join(given)}, or set them in the fleet's scenario file"
        )
    if phases is not None and timing != "exponential":
        raise ScenarioError(f"--phases {phases}: phases shape the exponential timing's step durations; add --timing exponential")
    world = world_of(scenario)
    changes: dict[str, Any] = {}
    if timing is not None:
        changes["timing"] = timing
        if timing != "exponential":
            changes["phases"] = 1  # (a World's own Erlang phases time exponential steps only)
    if phases is not None:
        changes["phases"] = phases
    if no_signals:
        changes["signals"] = False
    return replace(scenario, world=replace(world, **changes))


def _simulate(args: Any, scenario: Scenario, err: IO[str], show: bool, t_wall: float) -> RunResult:
    """One robot's run in the SimPy world, its trace written to ``args.trace`` once complete."""
    from desmon.sim.engine import SimWorld
    from desmon.sim.trace import Trace

    with contextlib.ExitStack() as stack:
        line = stack.enter_context(_status_line(err))  # ended before the summary, or before an error's message
        progress = _reporter(line, t_wall) if show else None
        # the trace replaces an existing file only once the run is complete (nothing lost on an error)
        fh = stack.enter_context(replacing(args.trace)) if args.trace else None
        world = SimWorld(
            scenario, deployer=args.deployer, seed=args.seed or 0, until=args.until, trace=Trace(fh, keep=False), progress=progress,
            render_ahead={"on": True, "off": False}.get(getattr(args, "render_ahead", "auto")), run=run_of(args),
        )
        result = world.run()
        result.metrics["audits"] = world.audits
    return result


def _run_fleet(args: Any, scenario: Scenario, out: IO[str], err: IO[str], show: bool) -> int:
    """``desmon run`` on a fleet scenario (:mod:`desmon.sim.fleet`), its progress on one line:
    check the arguments, run the fleet, write the trace, print the summary (or ``--json``);
    exit 0 if every audit held, 1 otherwise."""
    from desmon.sim.fleet import simulate_fleet

    fleet = scenario.world
    if getattr(args, "render_ahead", "auto") != "auto":
        raise ScenarioError(f"--render-ahead applies to one robot's run; {scenario.name!r} is a fleet of {len(fleet.robots)}: drop --render-ahead")
    if getattr(args, "plot", None):
        raise ScenarioError(f"--plot draws one robot's timeline; {scenario.name!r} is a fleet of {len(fleet.robots)}: drop --plot")
    if args.until is not None and args.until > fleet.horizon:
        raise ScenarioError(
            f"--until {exact(args.until)}: the fleet's shift ends at its horizon of {exact(fleet.horizon)} s; give --until at most that"
        )
    with _status_line(err) as line:  # ended before the summary, or before an error's message
        progress = _reporter(line, time.perf_counter()) if show else None
        with contextlib.ExitStack() as stack:
            fh = stack.enter_context(replacing(args.trace)) if args.trace else None
            result = simulate_fleet(scenario, deployer=args.deployer, seed=args.seed or 0, until=args.until, trace=fh, progress=progress, guard=args.guard)
    if args.json:
        out.write(json.dumps(fleet_json(result, world_given(args)), indent=2) + "\n")
    else:
        out.write(format_fleet_summary(result))
        if args.trace:
            out.write(f"Trace: {args.trace}\n")
    warn_uncovered(scenario, float(args.until) if args.until is not None else None)
    return 1 if result.violations else 0


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


# --------------------------------------------------------------------------- presenters


def _fmt(v: Any) -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        if 0 < abs(v) < 0.0005:  # (three decimals would print a figure that is not 0 as 0)
            return f"{v:.3g}"
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
    lines += exposure_lines(m)
    order = [
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
        ("memory over capacity (s) [1]", "overcommit_s"),
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
        lines.append("Invariants: all held at every quiescent point (after each reaction with no further stimulus pending); "
                     "single-instance, no-overcommit and fixed also after every start.")
    return "\n".join(lines) + "\n"


def exposure_lines(m: dict[str, Any]) -> list[str]:
    """The exposure figure with its denominator and its causes (docs/design.md, the
    definition of :mod:`desmon.deployment.exposure`)."""
    from desmon.deployment.exposure import CAUSE_TEXT

    risky, unmon, excluded = m["risky_time_s"], m["unmonitored_exposure_s"], m.get("excluded_s") or 0.0
    if excluded and risky - excluded > 0:
        share = f" = {100.0 * unmon / (risky - excluded):.1f} % of the risky time not excluded ({_fmt(risky - excluded)} s)"
    else:
        share = f" = {100.0 * unmon / risky:.1f} % of the risky time" if risky > 0 and not excluded else ""
    lines = [
        f"  {'risky time (s)':<30} {_fmt(risky)}   (an object in the hand)",
        f"  {'unmonitored exposure (s)':<30} {_fmt(unmon)}{share}",
    ]
    for c, v in m.get("unmonitored_by_cause_s", {}).items():
        if v > 0:
            lines.append(f"    {CAUSE_TEXT[c]:<32} {_fmt(v)}")
    if m.get("excluded_s"):
        lines.append(f"  {'excluded on purpose (s)':<30} {_fmt(m['excluded_s'])}   (risky actions declared watched=False: part of the risky time, never unmonitored)")
    return lines


def _signal_status(r: RunResult) -> list[str]:
    """What the exposure figures mean in this run: signals off, or graphs without a signal model."""
    m = r.metrics
    out: list[str] = []
    if not m.get("signals", True):
        why = " (the world is derived from the scripted timeline)" if r.scenario.world is None else ""
        out = [
            f"Signals: off{why}: no detector is simulated; a running, warmed-up deployment that",
            "  could detect a slip counts as watching, and slips are injected but not detected.",
        ]
    given = m.get("given_detection_rates") or {}
    if given:
        rates = "; ".join(f"{g} {p:g}" for g, p in given.items())
        out += [
            f"GIVEN DETECTION RATES: {rates} (World.detection_rates)",
            "  these have no signal model: each catches a slip it watches with that probability, a seeded draw, not a signal.",
        ]
    missing = m.get("no_signal_model") or {}
    if not missing:
        return out
    graphs = "; ".join(f"{g} (reads {', '.join(kinds)})" for g, kinds in missing.items())
    return out + [
        f"NO SIGNAL MODEL: {graphs}",
        "  these run and use memory but cannot detect a slip, so they never count as watching (their time",
        "  is unmonitored exposure, cause: cannot detect): map the kinds in World(signal_kinds=...).",
    ]


def summary_json(r: RunResult, wall: float | None = None, world: tuple[str, ...] = ()) -> dict[str, Any]:
    """The ``desmon run --json`` summary of a run; ``world``: how the command line changed the
    scenario's world (:func:`~desmon.cli.common.world_given`)."""
    return {
        "scenario": r.scenario.name,
        "world": list(world),
        "deployer": r.deployer,
        "seed": r.seed,
        "horizon_s": r.horizon,
        "wall_s": None if wall is None else round(wall, 3),
        "decisions": r.decisions,
        "errors": [e.to_json() for e in r.errors],
        "violations": [{"t": t, "invariant": n, "message": m} for t, n, m in r.violations],
        "metrics": r.metrics,
    }


def _fmt_spread(s: dict[str, float], unit: str = "", scale: float = 1.0, digits: int = 1) -> str:
    f = lambda v: f"{v * scale:.{digits}f}"  # noqa: E731
    return f"{f(s['mean'])}{unit} [{f(s['min'])}-{f(s['max'])}]"


def _fleet_exposure_interval(r: FleetResult) -> str:
    """The line under a fleet's mean exposure per robot: its interval over the robots
    (:func:`desmon.sim.fleet.FleetResult`'s metrics, as ``--json`` gives it)."""
    from desmon.sim.fleet import FLEET_CONFIDENCE

    iv = r.metrics["exposure_per_robot_s"]["interval"]
    head = f"    ({100 * FLEET_CONFIDENCE:g} % interval of the mean: "
    if iv is None:
        return head + "none from one robot)"
    return f"{head}[{iv['low']:.1f}, {iv['high']:.1f}], {iv['method']})"


def _count(n: int, what: str) -> str:
    return f"{n} {what}" if n == 1 else f"{n} {what}s"


def format_fleet_summary(r: FleetResult) -> str:
    """The human-readable report of ``desmon run`` on a fleet scenario."""
    from desmon.deployment.exposure import CAUSE_TEXT

    m = r.metrics
    lines = [
        f"{r.scenario.name} -- SimPy fleet, {_count(m['robots'], 'robot')}, {_count(m['edges'], 'edge server')}, deployer {r.deployer}, "
        f"seed {r.seed}, {r.horizon:g} s simulated in {m['wall_s']:.2f} s wall ({m['realtime_ratio']:g}x real time)",
        "Signals: off: no detector is simulated; a running, warmed-up valid deployment counts as monitoring.",
        "",
        "Per robot, mean [min-max] over the robots:",
        f"  unmonitored exposure (s)       {_fmt_spread(m['exposure_per_robot_s'])}",
        _fleet_exposure_interval(r),
        *(f"    {CAUSE_TEXT[c]:<31} {_fmt_spread(v)}" for c, v in m["exposure_by_cause_per_robot_s"].items() if v["max"] > 0),
        f"  risky time (s)                 {_fmt_spread(m['risky_time_per_robot_s'])}",
        *([f"  excluded on purpose (s)        {_fmt_spread(m['excluded_per_robot_s'])}   (watched=False: risky, never unmonitored)"]
          if m["excluded_per_robot_s"]["max"] > 0 else []),
        "Edge servers, mean [min-max] over the servers:",
        f"  memory share, time average     {_fmt_spread(m['edge_memory_share_mean'], '%', 100.0)}",
        f"  memory share, peak             {_fmt_spread(m['edge_memory_share_peak'], '%', 100.0)}",
        f"  seconds with a detector        {_fmt_spread(m['edge_busy_s'], '', 1.0, 0)}",
        f"  detector starts on edges       {m['edge_starts']}",
        "Errors by kind (all robots):",
    ]
    lines += [f"  {k:<30} {n}" for k, n in m["errors"].items()] or ["  (none)"]
    lines += [
        "Fleet totals:",
        f"  reactions / audits             {m['reactions']} / {m['audits']}",
        f"  starts / failed starts / stops {m['starts']} / {m['start_failures']} / {m['stops']}",
        f"  migrations                     {m['migrations']}",
        f"  slips injected                 {m['slips_injected']}",
        f"  repository changes             {m['repository_changes']}",
        f"  peak memory (RSS, MB)          {m['peak_rss_mb']:g}",
        "",
    ]
    if r.violations:
        lines.append(f"INVARIANTS VIOLATED ({len(r.violations)}):")
        for t, robot, name, msg in r.violations[:10]:
            lines.append(f"  t={t:.3f}s {robot} {name}: {msg}")
        if len(r.violations) > 10:
            lines.append(f"  ... {len(r.violations) - 10} more")
    else:
        lines.append("Invariants: all held at every quiescent point of every robot (edge servers audited with every robot's load); "
                     "single-instance, no-overcommit and fixed also after every start.")
    return "\n".join(lines) + "\n"


def fleet_json(r: FleetResult, world: tuple[str, ...] = ()) -> dict[str, Any]:
    """The ``desmon run --json`` summary of a fleet run (``world``: as :func:`summary_json`'s)."""
    return {
        "scenario": r.scenario.name,
        "world": list(world),
        "deployer": r.deployer,
        "seed": r.seed,
        "horizon_s": r.horizon,
        "metrics": r.metrics,
        "robots": r.robots,
        "violations": [{"t": t, "robot": robot, "invariant": n, "message": m} for t, robot, n, m in r.violations],
    }
