"""``desmon verify``: explore every interleaving of a scenario's bounded events with the
checker and check the invariants; ``--replay FILE.json`` re-runs a saved counterexample
instead (:mod:`desmon.cli.verify_replay`).

Long work stops well: ``--timeout`` and ``--max-memory`` end a search INCOMPLETE (exit 3)
with what it explored, and Ctrl-C ends it with its partial result (it still writes
``--json``), exit 130, without a traceback.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path
from typing import Any

from desmon.cli.common import CEX_FILE, MAX_STATES, Subparsers, deployer_arg, load_scenario_of, scenario_arg, warn_uncovered, run_of
from desmon.paths import GENERATED_TEST_HEAD
from desmon.cli.options import Input, add_output, megabytes, positive_int, positive_seconds, worker_count
from desmon.errors import CheckerError
from desmon.verify import engines

__all__ = ["add_parser", "run", "check_megabytes", "workers_for", "SEARCH_OPTIONS"]

#: ``verify`` options of the search, meaningless with ``--replay``: dest -> (flag, its value when not given)
SEARCH_OPTIONS = {
    "invariant": ("--invariant", None), "keep_going": ("--continue", False), "max_states": ("--max-states", MAX_STATES),
    "max_depth": ("--max-depth", None), "timeout": ("--timeout", None), "max_memory": ("--max-memory", None),
    "symmetry": ("--symmetry", False), "workers": ("--workers", 1), "engine": ("--engine", "auto"),
    "json": ("--json", None), "pytest": ("--pytest", None), "stats": ("--stats", False),
}


def add_parser(sub: Subparsers) -> None:
    p = sub.add_parser("verify", help="explore every interleaving of events and check the invariants")
    scenario_arg(p)
    deployer_arg(p)
    p.add_argument("--invariant", action="append", default=None, help="check only this invariant (repeatable)")
    p.add_argument("--continue", dest="keep_going", action="store_true", help="collect the shortest counterexample of each invariant broken, as --invariant NAME for each would: the "
                   "search goes on past the states that break one, and a reaction that breaks several inside it reports each")
    _add_limits(p)
    p.add_argument("--symmetry", action="store_true", help="canonicalise interchangeable platforms")
    p.add_argument("--together", action="store_true",
                   help="also explore two changes answered by one reaction, as the world answers the changes of one instant "
                        "(the scenario's Bounds(together=True); the direct engine)")
    p.add_argument(
        "--workers", type=worker_count, default=1, metavar="N",
        help="direct engine only (--engine direct): expand its BFS levels of 256 states or more in N forked "
        "processes, same result for any N; it can pay only on levels of thousands of states with N idle cores. "
        "With --engine auto the table engine runs, in one process (faster on every model measured: docs/deployers.md), "
        "and --workers is not used",
    )
    p.add_argument(
        "--engine", choices=engines.names(), default=engines.AUTO,
        help=engines.described(),
    )
    add_output(p, "--json", suffixes=(".json",), default=None, metavar="FILE.json", help="write the counterexample(s) as JSON states")
    add_output(p, "--pytest", suffixes=(".py",), default=None, metavar="FILE.py", written_head=GENERATED_TEST_HEAD,
               help="write a pytest replaying the counterexample (over a file only if desmon wrote it)")
    add_output(
        p, "--plot", suffixes=(".png",), default=None, metavar="FILE.png",
        help="draw the shortest counterexample as repository snapshots (with --replay: the replayed one)",
    )
    p.add_argument("--no-progress", action="store_true")
    p.add_argument(
        "--stats", action="store_true",
        help="also print the search's throughput: states/s, resident memory per state (bytes/state: what the search "
        "added to the process's resident size, over its states) and the table engine's recorded runs of the core "
        '(with --json: also under the key "stats")',
    )
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
    p.set_defaults(handler=run, _inputs=(*p.get_default("_inputs"), Input("replay", CEX_FILE)))


def _add_limits(p: argparse.ArgumentParser) -> None:
    """The budgets after which ``desmon verify`` stops INCOMPLETE (exit 3)."""
    p.add_argument("--max-states", type=positive_int, default=MAX_STATES, help="stop INCOMPLETE (exit 3) once this many states are found (the state being expanded adds all its successors first, so the count printed may pass N)")
    p.add_argument("--max-depth", type=positive_int, default=None, help="explore at most this many events deep (default: no limit)")
    p.add_argument("--timeout", type=positive_seconds, default=None, help="stop INCOMPLETE (exit 3) after this many seconds (default: no limit)")
    p.add_argument(
        "--max-memory", type=megabytes, default=None, metavar="MB",
        help="memory budget: stop INCOMPLETE (exit 3) once the search's resident memory (workers included) exceeds it",
    )


def run(args: argparse.Namespace) -> int:
    """``desmon verify``: a search, or with ``--replay`` a saved counterexample re-run."""
    if args.replay is not None:
        for dest, (flag, unset) in SEARCH_OPTIONS.items():
            if getattr(args, dest) != unset:
                raise CheckerError(f"{flag} sets up a search, and --replay replays one saved counterexample instead: drop {flag}")
        from desmon.cli.verify_replay import replay_counterexample

        return replay_counterexample(args)
    if args.counterexample is not None:
        raise CheckerError("--counterexample N picks a counterexample of a saved file: also give --replay FILE.json")
    return _search(args)


def _positive(name: str, value: float | int | None) -> None:
    if value is not None and value <= 0:
        raise CheckerError(f"--{name} must be positive, got {value}")


def check_megabytes(flag: str, value: float | None) -> None:
    """A memory budget: a finite number of MB above 0 (or None: no budget)."""
    if value is not None and not (math.isfinite(value) and value > 0):
        raise CheckerError(f"{flag} {value:g}: give the memory budget as a finite number of MB above 0, e.g. {flag} 2000")


def workers_for(args: argparse.Namespace) -> int:
    """The worker processes the search gets: ``--workers`` runs the *direct* engine in
    parallel, so under ``--engine auto`` (the table engine, one process, with or without
    ``--symmetry``) it is not used and a one-line note says so: the table engine was faster than
    the direct engine with 2 workers on every model measured (docs/deployers.md, "--workers")."""
    workers = getattr(args, "workers", 1)
    if workers > 1 and getattr(args, "engine", "auto") == "auto":
        print(
            f"desmon verify: note: --workers {workers} not used: --engine auto runs the table engine, in one process, which "
            f"beat the direct engine in {workers} processes on every model measured; to run the direct engine in parallel "
            f"anyway: --engine direct --workers {workers}",
            file=sys.stderr,
        )
        return 1
    return workers


def _search(args: argparse.Namespace) -> int:
    """The search, its report and its files: the one place the command uses the checker."""
    # --timeout counts the process's start-up (desmon as a program), the imports and the scenario's loading too
    started = getattr(args, "_started", None) or time.perf_counter()
    from desmon.verify.checker import check, release, system_of

    _positive("max-states", args.max_states)
    _positive("max-depth", args.max_depth)
    _positive("timeout", args.timeout)
    _positive("workers", getattr(args, "workers", 1))
    max_memory = getattr(args, "max_memory", None)
    check_megabytes("--max-memory", max_memory)
    scenario = load_scenario_of(args)
    system = system_of(scenario, args.deployer, invariants=args.invariant, symmetry=bool(getattr(args, "symmetry", False)), run=run_of(args))
    result = check(
        system,
        max_states=args.max_states,
        max_depth=args.max_depth,
        timeout=args.timeout,
        timeout_spent=time.perf_counter() - started,
        max_memory=max_memory,
        keep_going=args.keep_going,
        progress=not args.no_progress,
        workers=workers_for(args),
        engine=getattr(args, "engine", "auto"),
    )
    try:
        _report(args, result)
        warn_uncovered(scenario)
        if not result.interrupted:  # Ctrl-C: the partial result and its JSON, and nothing slower
            _write_outputs(args, scenario, result, system.core.deployer, system.bounds)
        else:
            skipped = [o for o in (getattr(args, "plot", None), args.pytest) if o]
            if skipped:
                print(f"interrupted: {' and '.join(skipped)} not written (run again without Ctrl-C to write them)")
    finally:
        release(system, result)  # the process exits next: free the memos now, not in a slow final collection
    return result.exit_code


def _report(args: argparse.Namespace, result: Any) -> None:
    """The search's report, and ``--json``."""
    from desmon.model.params import parse_assignments
    from desmon.paths import replacing
    from desmon.verify.report import format_result, format_stats, result_to_json, stats_to_json

    print(format_result(result), end="", flush=True)
    stats = getattr(args, "stats", False)
    if stats:
        print(format_stats(result), flush=True)
    if args.json:
        out = result_to_json(result, parse_assignments(getattr(args, "param", None)))
        if stats:
            out["stats"] = stats_to_json(result)
        with replacing(args.json) as fh:  # (a write that fails leaves the file there was)
            fh.write(json.dumps(out, indent=2) + "\n")
        print(f"wrote {args.json}")


def _write_outputs(args: argparse.Namespace, scenario: Any, result: Any, deployer: Any, bounds: Any) -> None:
    """``--plot`` and ``--pytest`` of the search's counterexamples (none when the deployer crashed)."""
    from desmon.verify.search import CRASHED

    plot = getattr(args, "plot", None)
    crashed = result.verdict == CRASHED  # the path reaches a reaction that failed: nothing to draw or to replay as a test
    if crashed and (plot or args.pytest):
        print(f"the deployer crashed: {' and '.join(o for o in (plot, args.pytest) if o)} not written (fix the deployer, then re-run)")
    elif plot:
        if result.counterexamples:
            from desmon.verify.plot import plot_counterexample

            shortest = min(result.counterexamples, key=lambda c: c.length)
            out = plot_counterexample(scenario, deployer, bounds, shortest, plot)
            print(f"wrote {out} ({shortest.invariant}, {shortest.length} step{'s' if shortest.length != 1 else ''})")
        else:
            print(f"no counterexample: {plot} not written")
    if args.pytest and not crashed:
        if result.counterexamples:
            from desmon.model.params import parse_assignments
            from desmon.paths import replacing
            from desmon.verify.report import counterexample_pytest

            path = str(Path(args.scenario).resolve())
            params = parse_assignments(getattr(args, "param", None))
            with replacing(args.pytest) as fh:
                fh.write(counterexample_pytest(result, path, bounds.start_action(scenario), params))
            print(f"wrote {args.pytest}")
        else:
            print(f"no counterexample: {args.pytest} not written")
