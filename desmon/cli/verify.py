"""``desmon verify`` and ``desmon fuzz``: the CLI handlers (they return the exit code).

Long work stops well: ``--timeout`` and ``--max-memory`` end a search INCOMPLETE (exit 3)
with what it explored, and Ctrl-C ends either command with its partial result (verify
still writes ``--json``), exit 130, without a traceback.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

from desmon.errors import CheckerError

__all__ = ["verify_command", "fuzz_command", "check_megabytes", "workers_for"]


def _positive(name: str, value: float | int | None) -> None:
    if value is not None and value <= 0:
        raise CheckerError(f"--{name} must be positive, got {value}")


def check_megabytes(flag: str, value: float | None) -> None:
    """A memory budget: a finite number of MB above 0 (or None: no budget)."""
    if value is not None and not (math.isfinite(value) and value > 0):
        raise CheckerError(f"{flag} {value:g}: give the memory budget as a finite number of MB above 0, e.g. {flag} 2000")


def workers_for(args: argparse.Namespace) -> int:
    """The worker processes the search gets: ``--workers`` runs the *direct* engine in
    parallel, so under ``--engine auto`` without ``--symmetry`` (the table engine, one
    process) it is not used and a one-line note says so: the table engine was faster than
    the direct engine with 2 workers on every model measured (docs/deployers.md, "--workers")."""
    workers = getattr(args, "workers", 1)
    if workers > 1 and getattr(args, "engine", "auto") == "auto" and not getattr(args, "symmetry", False):
        import sys

        print(
            f"desmon verify: note: --workers {workers} not used: --engine auto runs the table engine, in one process, which "
            f"beat the direct engine in {workers} processes on every model measured; to run the direct engine in parallel "
            f"anyway: --engine direct --workers {workers}",
            file=sys.stderr,
        )
        return 1
    return workers


def verify_command(args: argparse.Namespace) -> int:
    # --timeout counts the process's start-up (desmon as a program), the imports and the scenario's loading too
    started = getattr(args, "_started", None) or time.perf_counter()
    from desmon.loader import load_from_args
    from desmon.model.params import parse_assignments
    from desmon.verify.checker import Checker
    from desmon.verify.report import counterexample_pytest, format_result, result_to_json
    from desmon.verify.search import CRASHED

    _positive("max-states", args.max_states)
    _positive("max-depth", args.max_depth)
    _positive("timeout", args.timeout)
    _positive("workers", getattr(args, "workers", 1))
    max_memory = getattr(args, "max_memory", None)
    check_megabytes("--max-memory", max_memory)
    scenario = load_from_args(args)
    checker = Checker(scenario, args.deployer, invariants=args.invariant, symmetry=bool(getattr(args, "symmetry", False)))
    result = checker.run(
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
    print(format_result(result), end="", flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps(result_to_json(result, parse_assignments(getattr(args, "param", None))), indent=2) + "\n")
        print(f"wrote {args.json}")
    if result.interrupted:  # Ctrl-C: the partial result and its JSON, and nothing slower
        checker.release()
        return result.exit_code
    crashed = result.verdict == CRASHED  # the path reaches a reaction that failed: nothing to draw or to replay as a test
    if crashed and (getattr(args, "plot", None) or args.pytest):
        print(f"the deployer crashed: {' and '.join(o for o in (getattr(args, 'plot', None), args.pytest) if o)} not written (fix the deployer, then re-run)")
    elif getattr(args, "plot", None):
        if result.counterexamples:
            from desmon.verify.plot import plot_counterexample

            shortest = min(result.counterexamples, key=lambda c: c.length)
            out = plot_counterexample(scenario, checker.core.deployer, checker.bounds, shortest, args.plot)
            print(f"wrote {out} ({shortest.invariant}, {shortest.length} step{'s' if shortest.length != 1 else ''})")
        else:
            print(f"no counterexample: {args.plot} not written")
    if args.pytest and not crashed:
        if result.counterexamples:
            path = str(Path(args.scenario).resolve())
            params = parse_assignments(getattr(args, "param", None))
            Path(args.pytest).write_text(counterexample_pytest(result, path, checker.bounds.start_action(scenario), params))
            print(f"wrote {args.pytest}")
        else:
            print(f"no counterexample: {args.pytest} not written")
    checker.release()  # the process exits next: free the memos now, not in a slow final collection
    return result.exit_code


def fuzz_command(args: argparse.Namespace) -> int:
    from desmon.verify.fuzz import fuzz

    if args.examples <= 0:
        raise CheckerError(f"--examples must be positive, got {args.examples}")
    from desmon.loader import load_from_args

    scenario = load_from_args(args)
    outcome = fuzz(scenario, args.deployer, examples=args.examples, seed=args.seed, progress=not args.no_progress)
    print(outcome.text, end="")
    return outcome.exit_code
