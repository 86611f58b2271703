"""The ``desmon`` command line: argument parsing and presentation only.

Every subcommand's work lives in the engines; a handler here parses, calls, prints.
Exit codes: 0 success / property holds, 1 a violation or failed check, 2 bad input,
3 incomplete (checker limits reached), 4 the deployer crashed in a reachable state (it
raised, yielded a wrong command or never ended: :mod:`desmon.deployment.guard`). A :class:`~desmon.errors.DesmonError` is printed
as one line ``desmon: error: ...`` without a traceback.
"""

from __future__ import annotations

import argparse
import math
import re
import sys
from typing import Any, Callable, NoReturn, Sequence, TypeAlias

from desmon.errors import DesmonError
from desmon.options import (
    HelpFormatter,
    Input,
    add_input,
    add_output,
    add_resolved,
    add_window,
    non_negative_int,
    positive_int,
    positive_seconds,
    preflight,
    worker_count,
)
from desmon.paths import SCENARIO_FILE, TRACE_FILE, plan_outputs

__all__ = ["main", "build_parser"]

EXIT_OK, EXIT_VIOLATED, EXIT_USAGE, EXIT_INCOMPLETE = 0, 1, 2, 3

#: ``show --format`` -> the file suffixes it writes (the first is the usual one).
SHOW_FORMATS = {"png": (".png",), "dot": (".dot", ".gv"), "graphml": (".graphml",), "json": (".json",), "cypher": (".cypher", ".cql")}
RUN_WINDOW = ("--plot-from", "--plot-to")
MAX_STATES = 2_000_000  # verify --max-states when not given
CEX_FILE = ("counterexample file", "write one with: desmon verify SCENARIO --json cex.json")
#: ``verify`` options of the search, meaningless with ``--replay``: dest -> (flag, its value when not given)
SEARCH_OPTIONS = {
    "invariant": ("--invariant", None), "keep_going": ("--continue", False), "max_states": ("--max-states", MAX_STATES),
    "max_depth": ("--max-depth", None), "timeout": ("--timeout", None), "max_memory": ("--max-memory", None),
    "symmetry": ("--symmetry", False), "workers": ("--workers", 1), "engine": ("--engine", "auto"),
    "json": ("--json", None), "pytest": ("--pytest", None),
}


def _one_line(text: object) -> str:
    """``text`` on one line (a message may quote a user's value holding a newline)."""
    return " ".join(str(text).split())


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line: ``desmon: error: COMMAND: ...; see: desmon COMMAND --help``,
    ``--help`` shows every option's default (:class:`~desmon.options.HelpFormatter`), and an
    option must be written in full (no abbreviations: a typo is refused, not guessed)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("formatter_class", HelpFormatter)
        kwargs.setdefault("allow_abbrev", False)  # --time is not silently --timeout
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_USAGE, _usage_error(self.prog, message))


def _usage_error(prog: str, message: str) -> str:
    """The one line for a usage error of ``prog`` ("desmon" or "desmon COMMAND")."""
    command = prog.removeprefix("desmon").strip()
    where = f"{command}: " if command else ""
    message = re.sub(r"^argument (\S+): must ", r"\1 must ", _one_line(message))  # "--seed must be ..., got -1"
    return f"desmon: error: {where}{message}; see: {prog} --help\n"


def _scenario_arg(p: argparse.ArgumentParser, help: str = "scenario file, e.g. scenarios/coffee_handover.py") -> None:
    add_input(p, "scenario", SCENARIO_FILE, help=help)
    p.add_argument(
        "-p", "--param", action="append", default=None, metavar="NAME=VALUE",
        help="set a parameter the scenario declares with parameters(...), e.g. -p hand_memory=384 (repeatable)",
    )


def _resolve_deployer(spec: str) -> object:
    from desmon.verify.deployers import resolve_deployer

    return resolve_deployer(spec)


def _deployer_arg(p: argparse.ArgumentParser, *, deadline: bool = True) -> None:
    from desmon.verify.deployers import MUTANT_PREFIX
    from desmon.verify.mutants import MUTANTS

    add_resolved(
        p, "--deployer", resolve=_resolve_deployer, default="desmon", metavar="SPEC",
        help="desmon (corrected, upgrades to a preferred detector break-before-make), "
        "desmon-keep-fallback (keeps a running fallback), paper (Algorithms 1 and 2 as published), "
        f"{MUTANT_PREFIX}:NAME (a seeded bug: {', '.join(MUTANTS)}), "
        "or your own: path/to/file.py:NAME or module:NAME (docs/deployers.md)",
    )
    p.add_argument(
        "--max-commands", type=positive_int, default=None, metavar="N",
        help="the most commands one reaction of the deployer may issue; more is a reaction that never ends, "
        "reported as the deployer's failure (default: 10000)",
    )
    if deadline:  # (verify has --timeout: its budget stops a reaction that runs too long)
        p.add_argument(
            "--max-reaction-seconds", type=positive_seconds, default=None, metavar="S",
            help="the longest the deployer's code may run without yielding a command or returning; longer is a "
            "reaction that never ends, reported as the deployer's failure (default: 60)",
        )


def _load_scripted(args: argparse.Namespace):  # type: ignore[no-untyped-def]
    """A scenario for the timeline-based commands (replay, explain, show): it needs a scripted timeline."""
    from desmon.errors import ScenarioError
    from desmon.loader import load_from_args

    path = args.scenario
    scenario = load_from_args(args)
    if not scenario.timeline:
        raise ScenarioError(
            f"{path}: scenario {scenario.name!r} has no scripted timeline, so there is no moment to replay; "
            f"simulate it with: desmon run {path} --trace run.jsonl (and desmon plot run.jsonl)"
        )
    return scenario


def _cmd_replay(args: argparse.Namespace) -> int:
    from desmon.sim.replay import format_replay, replay

    scenario = _load_scripted(args)
    result = replay(scenario, args.deployer)
    print(format_replay(result), end="")
    return EXIT_VIOLATED if result.violations else EXIT_OK


def _cmd_explain(args: argparse.Namespace) -> int:
    from desmon.deployment.validity import acceptable_platforms
    from desmon.errors import QueryError
    from desmon.repository.query import RepositoryQuery
    from desmon.sim.replay import replay

    scenario = _load_scripted(args)
    if "," in (args.at or ""):
        raise QueryError(f"--at {args.at!r}: explain answers for one moment; give one time or label")
    [(when, at)] = _resolve_times(scenario, args.at)
    if scenario.model.spec(args.graph) is None:
        known = ", ".join(s.graph for s in scenario.model.specs)
        raise QueryError(f"{args.scenario}: no deployment specification for {args.graph!r}; known: {known}")
    timeline = tuple(te for te in scenario.timeline if te.time <= at)
    from dataclasses import replace

    result = replay(replace(scenario, timeline=timeline), args.deployer)
    validity = acceptable_platforms(RepositoryQuery(result.repo), args.graph)
    fixed = scenario.model.spec(args.graph).fixed_platform  # type: ignore[union-attr]
    print(f"{args.graph} at {when} ({args.deployer.name} deployer):")
    if fixed is not None:
        print(f"fixed deployment: only its EXECUTABLE_ON platform {fixed} is considered")
    print(validity.explain())
    return EXIT_OK


def _resolve_times(scenario, spec: str | None) -> list[tuple[str, float]]:  # type: ignore[no-untyped-def]
    from desmon.errors import ScenarioError

    if spec is None:
        end = scenario.timeline[-1].time if scenario.timeline else 0.0
        return [(f"t={end:g}s", end)]
    labels = {te.label: te.time for te in scenario.timeline if te.label}
    out = []
    for part in spec.split(","):
        part = part.strip()
        if part in labels:
            out.append((f"{part} (t={labels[part]:g}s)", labels[part]))
            continue
        try:
            t = float(part)
        except ValueError:
            raise ScenarioError(
                f"--at {part!r} is neither a time in seconds nor a timeline label ({', '.join(labels) or 'none'})"
            ) from None
        if not math.isfinite(t):
            raise ScenarioError(f"--at {part}: give a finite time in seconds or a timeline label ({', '.join(labels) or 'none'})")
        first = scenario.timeline[0].time
        if t < first:
            raise ScenarioError(f"--at {part}: the timeline starts at t={first:g}s; give a time at or after it")
        out.append((f"t={t:g}s", t))
    return out


def _cmd_show(args: argparse.Namespace) -> int:
    import json

    from desmon.errors import ScenarioError
    from desmon.paths import check_output_file, replacing
    from desmon.repository.export import graph_to_cypher, graph_to_dot
    from desmon.repository.store import graph_to_graphml, graph_to_json
    from desmon.sim.replay import replay

    scenario = _load_scripted(args)
    moments = _resolve_times(scenario, args.at)
    result = replay(scenario, args.deployer)
    snaps = []
    for title, t in moments:
        snap = result.repo.snapshot(at=t)
        ctx = [d["name"] for n, d in snap.nodes(data=True) if d.get("label") == "Context" and any(True for _ in snap.in_edges(n))]
        errors = [f"{e.kind}: {e.graph}" for step in result.steps if step.time == t for e in step.errors]
        head = f"{scenario.name} {title}" + (f"  context: {ctx[0]}" if ctx else "")
        snaps.append((head + "".join(f"\nerror raised: {e}" for e in errors), snap))
    fmt = args.format  # preflight set it from -o when --format was not given
    if fmt != "png" and len(snaps) > 1:
        raise ScenarioError(f"--format {fmt} writes one snapshot: give one --at, or use --format png for side-by-side")
    out = args.output
    if out is None and fmt in ("png", "graphml"):  # binary formats go to a file named after the scenario
        out = str(check_output_file(f"{scenario.name}-snapshot{SHOW_FORMATS[fmt][0]}", "-o", SHOW_FORMATS[fmt], [args.scenario]))
    if fmt == "png":
        from desmon.viz.snapshot import draw_snapshots

        draw_snapshots(snaps, out, full=result.repo.graph, columns=min(2, len(snaps)))
        print(f"wrote {out}")
        return EXIT_OK
    title, snap = snaps[0]
    if fmt == "graphml":
        graph_to_graphml(snap, str(out))
        print(f"wrote {out}")
        return EXIT_OK
    text = {
        "json": lambda: json.dumps(graph_to_json(snap), indent=2, sort_keys=True) + "\n",
        "dot": lambda: graph_to_dot(snap, title),
        "cypher": lambda: graph_to_cypher(snap),
    }[fmt]()
    if out:
        with replacing(out) as fh:
            fh.write(text)
        print(f"wrote {out}")
    else:
        sys.stdout.write(text)
    return EXIT_OK


def _cmd_evaluate(args: argparse.Namespace) -> int:
    from desmon.detectors.evaluation import run_evaluate

    return run_evaluate(
        trials=args.trials, seed=args.seed, as_json=args.json, progress=not args.no_progress, out=sys.stdout,
        seeds=args.seeds,
    )


def _draw_trace(trace: str, out: str, start: float | None, end: float | None, flags: tuple[str, str] = ("--from", "--to")) -> None:
    from desmon.viz.timeline import build_timeline, plot_timeline, read_trace

    records = read_trace(trace)
    plot_timeline(build_timeline(records, start, end, flags=flags), out)
    print(f"wrote {out}", file=sys.stderr)
    if not records[0].get("platforms"):  # drawn, but say why the picture has no platform lanes
        print(f"desmon: note: {trace} declares no platforms in its run record: only the context lane is drawn", file=sys.stderr)


def _cmd_plot(args: argparse.Namespace) -> int:
    _draw_trace(args.trace, args.output, args.start, args.end)
    return EXIT_OK


def _cmd_run(args: argparse.Namespace) -> int:
    import importlib
    import os
    import tempfile

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
        command = importlib.import_module("desmon.sim.command")
        code = int(command.run_command(args, before_run=window_fits if args.plot else None))
        if args.plot and code in (EXIT_OK, EXIT_VIOLATED):
            _draw_trace(args.trace, args.plot, args.plot_from, args.plot_to, RUN_WINDOW)
        return code
    finally:
        if tmp is not None and os.path.exists(tmp):
            os.unlink(tmp)


def _cmd_verify(args: argparse.Namespace) -> int:
    from desmon.errors import CheckerError

    if args.replay is not None:
        for dest, (flag, unset) in SEARCH_OPTIONS.items():
            if getattr(args, dest) != unset:
                raise CheckerError(f"{flag} sets up a search, and --replay replays one saved counterexample instead: drop {flag}")
        return _lazy("desmon.verify.replay_command", "replay_command")(args)
    if args.counterexample is not None:
        raise CheckerError("--counterexample N picks a counterexample of a saved file: also give --replay FILE.json")
    return _lazy("desmon.verify.command", "verify_command")(args)


def _lazy(module: str, func: str) -> Callable[[argparse.Namespace], int]:
    def handler(args: argparse.Namespace) -> int:
        import importlib

        return int(getattr(importlib.import_module(module), func)(args))

    return handler


_Subparsers: TypeAlias = "argparse._SubParsersAction[argparse.ArgumentParser]"


def build_parser() -> argparse.ArgumentParser:
    from desmon import __version__

    parser = _Parser(
        prog="desmon",
        description="Simulate, exhaustively check and fuzz the adaptive deployment of safety monitors.",
    )
    parser.add_argument("--version", action="version", version=f"desmon {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for add in (_add_replay, _add_explain, _add_show, _add_evaluate, _add_run, _add_plot, _add_verify, _add_fuzz, _add_explore):
        add(sub)
    from desmon.sweep.command import add_parsers as add_sweep_parsers  # sweep, sweep-plot (docs/sweeps.md)

    add_sweep_parsers(sub)
    parser.set_defaults(commands=tuple(sub.choices))
    return parser


def _add_replay(sub: _Subparsers) -> None:
    p = sub.add_parser("replay", help="replay a scenario's scripted timeline through the deployment core (no signals)")
    _scenario_arg(p)
    _deployer_arg(p)
    p.set_defaults(handler=_cmd_replay)


def _add_explain(sub: _Subparsers) -> None:
    p = sub.add_parser("explain", help="why each platform is accepted or rejected for a perception graph")
    _scenario_arg(p)
    p.add_argument("graph", help="perception graph, e.g. combined_slip_detector")
    p.add_argument("--at", default=None, help="seconds or a timeline label such as t1 (default: the timeline's end)")
    _deployer_arg(p)
    p.set_defaults(handler=_cmd_explain)


def _add_show(sub: _Subparsers) -> None:
    p = sub.add_parser("show", help="the repository graph at a time, as png, dot, graphml, json or cypher")
    _scenario_arg(p)
    p.add_argument("--at", default=None, help="seconds or timeline labels, comma-separated (e.g. t0,t1,t2,t3)")
    p.add_argument(
        "--format", default=None, choices=list(SHOW_FORMATS),
        help="what to write; when not given: the suffix of -o (.png .dot .graphml .json .cypher), else png",
    )
    add_output(
        p, "-o", "--output", formats=SHOW_FORMATS, default_format="png", default=None,
        help="output file, its suffix matching --format (text formats default to stdout)",
    )
    _deployer_arg(p)
    p.set_defaults(handler=_cmd_show)


def _add_evaluate(sub: _Subparsers) -> None:
    p = sub.add_parser("evaluate", help="detector x action table against Sanchez et al. 2016, and mission-level strategies")
    p.add_argument("--trials", type=positive_int, default=300, help="trials per cell")
    p.add_argument("--seed", type=non_negative_int, default=1, help="random seed; with --seeds, the first seed")
    p.add_argument(
        "--seeds", type=positive_int, default=None, metavar="N",
        help="run seeds SEED..SEED+N-1: per cell how many seeds pass, mission figures as mean [min..max]",
    )
    p.add_argument("--json", action="store_true", help="print JSON instead of tables")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(handler=_cmd_evaluate)


def _add_run(sub: _Subparsers) -> None:
    p = sub.add_parser("run", help="simulate a scenario in the SimPy world")
    _scenario_arg(p)
    p.add_argument("--seed", type=non_negative_int, default=0, help="random seed of the world (faults, slips, start failures)")
    p.add_argument("--until", type=positive_seconds, default=None, help="simulated seconds (default: the scenario's horizon)")
    _deployer_arg(p)
    add_output(p, "--trace", suffixes=(".jsonl",), default=None, metavar="FILE.jsonl", help="write the JSON Lines trace to this file")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.add_argument("--no-progress", action="store_true")
    add_output(
        p, "--plot", suffixes=(".png",), default=None, metavar="FILE.png",
        help="draw the timeline of the run to this PNG (needs desmon[plot])",
    )
    add_window(p, ("--plot-from", "plot_from"), ("--plot-to", "plot_to"), needs=("plot", "--plot"))
    p.set_defaults(handler=_cmd_run)


def _add_plot(sub: _Subparsers) -> None:
    p = sub.add_parser("plot", help="draw the timeline of a run's JSON Lines trace")
    add_input(p, "trace", TRACE_FILE, help="trace file written by desmon run --trace")
    add_output(p, "-o", "--output", suffixes=(".png",), default="timeline.png", metavar="FILE.png", help="PNG file")
    add_window(p, ("--from", "start"), ("--to", "end"))
    p.set_defaults(handler=_cmd_plot)


def _add_verify(sub: _Subparsers) -> None:
    p = sub.add_parser("verify", help="explore every interleaving of events and check the invariants")
    _scenario_arg(p)
    _deployer_arg(p, deadline=False)
    p.add_argument("--invariant", action="append", default=None, help="check only this invariant (repeatable)")
    p.add_argument("--continue", dest="keep_going", action="store_true", help="collect the first counterexample of each invariant")
    _add_verify_limits(p)
    p.add_argument("--symmetry", action="store_true", help="canonicalise interchangeable platforms")
    p.add_argument(
        "--workers", type=worker_count, default=1, metavar="N",
        help="direct engine only (--engine direct, --symmetry): expand its BFS levels of 256 states or more in N forked "
        "processes, same result for any N; it can pay only on levels of thousands of states with N idle cores. "
        "With --engine auto the table engine runs, in one process (faster on every model measured: docs/deployers.md), "
        "and --workers is not used",
    )
    p.add_argument(
        "--engine", choices=("auto", "table", "direct"), default="auto",
        help="table: run the real core once per distinct reading of a reaction and replay it (fast); "
        "direct: run it on every transition; auto: table unless --symmetry, else (or when the deployer reads platform "
        "facts outside the requirement checks) direct; the result is the same",
    )
    add_output(p, "--json", suffixes=(".json",), default=None, metavar="FILE.json", help="write the counterexample(s) as JSON states")
    add_output(p, "--pytest", suffixes=(".py",), default=None, metavar="FILE.py", help="write a pytest replaying the counterexample")
    add_output(
        p, "--plot", suffixes=(".png",), default=None, metavar="FILE.png",
        help="draw the shortest counterexample as repository snapshots (with --replay: the replayed one)",
    )
    p.add_argument("--no-progress", action="store_true")
    p.add_argument(
        "--replay", default=None, metavar="FILE.json",
        help="instead of a search, replay a counterexample saved by --json through the real core, step by step, and check "
        "the invariants on its final state: exit 1 if it still violates its invariant (or diverges from the saved states), "
        "0 if it no longer does; give the file's scenario, --deployer and -p parameters",
    )
    p.add_argument(
        "--counterexample", type=positive_int, default=None, metavar="N",
        help="with --replay: replay the file's N-th counterexample (default: the first)",
    )
    p.set_defaults(handler=_cmd_verify, _inputs=(*p.get_default("_inputs"), Input("replay", CEX_FILE)))


def _add_verify_limits(p: argparse.ArgumentParser) -> None:
    """The budgets after which ``desmon verify`` stops INCOMPLETE (exit 3)."""
    p.add_argument("--max-states", type=positive_int, default=MAX_STATES, help="stop INCOMPLETE (exit 3) after this many states")
    p.add_argument("--max-depth", type=positive_int, default=None, help="explore at most this many events deep (default: no limit)")
    p.add_argument("--timeout", type=positive_seconds, default=None, help="stop INCOMPLETE (exit 3) after this many seconds (default: no limit)")
    p.add_argument(
        "--max-memory", type=float, default=None, metavar="MB",
        help="memory budget: stop INCOMPLETE (exit 3) once the search's resident memory (workers included) exceeds it",
    )


def _add_fuzz(sub: _Subparsers) -> None:
    p = sub.add_parser("fuzz", help="hypothesis-generated failure sequences, shrunk on failure")
    _scenario_arg(p)
    _deployer_arg(p)
    p.add_argument("--examples", type=positive_int, default=200, help="failure sequences to generate")
    p.add_argument("--seed", type=non_negative_int, default=0, help="hypothesis seed (the same seed draws the same sequences)")
    p.add_argument("--no-progress", action="store_true")
    p.set_defaults(handler=_lazy("desmon.verify.command", "fuzz_command"))


def _add_explore(sub: _Subparsers) -> None:
    p = sub.add_parser(
        "explore",
        help="one self-contained HTML page to step through the scripted timeline or a counterexample (docs/tutorial.md)",
    )
    _scenario_arg(p)
    _deployer_arg(p)
    p.set_defaults(deployer=None)  # desmon, or the deployer a --from-json file was written with
    deployer = next(a for a in p._actions if a.dest == "deployer")
    deployer.help = f"{deployer.help} (default: desmon; with --from-json: the deployer the file was written with)"
    add_output(p, "-o", "--output", suffixes=(".html", ".htm"), default="explore.html", metavar="FILE.html", help="the page to write")
    p.add_argument("--verify", action="store_true", help="step through the shortest counterexample desmon verify finds instead of the timeline")
    p.add_argument("--invariant", default=None, metavar="NAME", help="with --verify: the shortest counterexample of this invariant")
    p.add_argument("--max-states", type=positive_int, default=None, metavar="N", help=f"with --verify: search at most N states (default: {MAX_STATES})")
    p.add_argument("--from-json", default=None, metavar="FILE.json", help="step through a counterexample saved by desmon verify --json")
    p.add_argument("--counterexample", type=positive_int, default=None, metavar="N", help="with --from-json: the file's N-th counterexample (default: the first)")
    p.add_argument("--no-progress", action="store_true", help="with --verify: no progress line")
    p.set_defaults(handler=_lazy("desmon.viz.explore_command", "explore_command"), _inputs=(*p.get_default("_inputs"), Input("from_json", CEX_FILE)))


def _process_age() -> float:
    """Seconds since this process started (interpreter start-up and imports included), 0 where unknown."""
    import os

    try:
        with open("/proc/self/stat", "rb") as fh:
            start_ticks = int(fh.read().rsplit(b")", 1)[1].split()[19])
        with open("/proc/uptime", "rb") as fh:
            uptime = float(fh.read().split()[0])
        return max(0.0, uptime - start_ticks / os.sysconf("SC_CLK_TCK"))
    except (OSError, ValueError, IndexError):
        return 0.0


def main(argv: Sequence[str] | None = None) -> int:
    import time

    # a budget (verify --timeout) counts from the start of the command: from the process's
    # start when desmon is the program (argv None), from this call when a caller runs it
    started = time.perf_counter() - (_process_age() if argv is None else 0.0)
    parser = build_parser()
    try:
        args, extra = parser.parse_known_args(argv)
    except SystemExit as exc:  # --help (0) or a one-line usage error (2)
        return exc.code if isinstance(exc.code, int) else EXIT_USAGE
    if extra:  # named with the command they were given to, unlike argparse's own message
        prog = f"desmon {args.command}" if getattr(args, "command", None) else "desmon"
        sys.stderr.write(_usage_error(prog, f"unrecognized arguments: {' '.join(extra)}"))
        return EXIT_USAGE
    args._started = started
    if not getattr(args, "handler", None):
        parser.print_help()
        print(f"desmon: error: no command given; choose one of {', '.join(args.commands)} (desmon COMMAND --help)", file=sys.stderr)
        return EXIT_USAGE
    from desmon.deployment.guard import EXIT_CRASHED, MAX_COMMANDS, MAX_REACTION_SECONDS, DeployerFault, commands_limit, reaction_deadline

    try:
        commands_limit(getattr(args, "max_commands", None) or MAX_COMMANDS)  # this command's (a process may run several)
        plan_outputs(())  # (preflight records this command's outputs)
        preflight(args)  # inputs, numbers, windows and output paths, before any long work
        if not hasattr(args, "max_reaction_seconds"):  # no deployer, or verify (its --timeout)
            return int(args.handler(args))
        with reaction_deadline(args.max_reaction_seconds or MAX_REACTION_SECONDS):
            return int(args.handler(args))
    except DeployerFault as exc:
        # (SimPy re-raises a process's exception as a copy caused by the original)
        if exc.initial or getattr(exc.__cause__, "initial", False):  # the deployer cannot run at all: bad input
            print(f"desmon: error: {_one_line(exc)}", file=sys.stderr)
            return EXIT_USAGE
        print(f"desmon: CRASHED: {_one_line(exc)}", file=sys.stderr)  # it failed in a state the run reached
        return EXIT_CRASHED
    except DesmonError as exc:
        print(f"desmon: error: {_one_line(exc)}", file=sys.stderr)
        return EXIT_USAGE
    except OSError as exc:  # an output file that cannot be written, a directory that does not exist
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"desmon: error: {_one_line(f'{where}cannot read or write: {exc.strerror or exc}; check the path')}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        print("desmon: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
