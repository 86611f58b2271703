"""The ``desmon`` command line: argument parsing and presentation only.

One module per command (:data:`COMMANDS`), each with ``add_parser(sub)`` (its options)
and ``run(args)`` (parse, call the library, print; it returns the exit code); the engines
take plain arguments and return result objects, and never see the command line.
Importing this package (and ``desmon --help``) loads no engine, nor networkx or numpy:
a command imports what it needs when it runs.

Exit codes: 0 success / property holds, 1 a violation or failed check, 2 bad input,
3 incomplete (checker limits reached), 4 the deployer crashed in a reachable state (it
raised, yielded a wrong command or never ended: :mod:`desmon.deployment.guard`). A :class:`~desmon.errors.DesmonError` is printed
as one line ``desmon: error: ...`` without a traceback.
"""

from __future__ import annotations

import argparse
import contextlib
import sys
from typing import Sequence

from desmon.cli import analyze, estimate, evaluate, explain, explore, fuzz, plot, replay, run, show, sweep, sweep_plot, verify
from desmon.cli.common import EXIT_USAGE, Parser, one_line, run_of, usage_error
from desmon.cli.options import preflight
from desmon.errors import DesmonError
from desmon.paths import WholeWrites

__all__ = ["main", "build_parser", "COMMANDS"]

#: the commands, in the order ``desmon --help`` lists them (sweep adds sweep and sweep-plot)
COMMANDS = (replay, explain, show, evaluate, run, estimate, plot, verify, analyze, fuzz, explore, sweep, sweep_plot)


def build_parser() -> argparse.ArgumentParser:
    from desmon import __version__

    parser = Parser(
        prog="desmon",
        description="Simulate, exhaustively check and fuzz the adaptive deployment of safety monitors.",
    )
    parser.add_argument("--version", action="version", version=f"desmon {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for command in COMMANDS:
        command.add_parser(sub)
    parser.set_defaults(commands=tuple(sub.choices))
    return parser


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
    if sys.stdout is None:  # started with its standard output closed (>&-): no verdict could be read
        if sys.stderr is not None:
            print("desmon: error: standard output is closed, where desmon writes its report; redirect it (> out.txt)", file=sys.stderr)
        return EXIT_USAGE
    parser = build_parser()
    try:
        args, extra = parser.parse_known_args(_signed_fractions(sys.argv[1:] if argv is None else list(argv)))
    except SystemExit as exc:  # --help (0) or a one-line usage error (2)
        return exc.code if isinstance(exc.code, int) else EXIT_USAGE
    if extra:  # named with the command they were given to, unlike argparse's own message
        prog = f"desmon {args.command}" if getattr(args, "command", None) else "desmon"
        sys.stderr.write(usage_error(prog, f"unrecognized arguments: {' '.join(extra)}"))
        return EXIT_USAGE
    args._started = started
    if not getattr(args, "handler", None):
        parser.print_help()
        print(f"desmon: error: no command given; choose one of {', '.join(args.commands)} (desmon COMMAND --help)", file=sys.stderr)
        return EXIT_USAGE
    return _dispatch(args)


#: the options whose value may be written as a percentage (``5%``): argparse takes a value
#: such as ``-5%`` for an option of its own, since it is no plain negative number
_FRACTION_OPTIONS = frozenset({"--within", "--confidence", "--alpha", "--beta"})


def _signed_fractions(argv: list[str]) -> list[str]:
    """``argv`` with ``--within -5%`` (and the other :data:`_FRACTION_OPTIONS`) written
    ``--within=-5%``: the option's own check then refuses the value, naming the fix."""
    out: list[str] = []
    i = 0
    while i < len(argv):
        token = argv[i]
        if token in _FRACTION_OPTIONS and i + 1 < len(argv) and argv[i + 1][:2] in {f"-{c}" for c in "0123456789."}:
            out.append(f"{token}={argv[i + 1]}")
            i += 2
            continue
        out.append(token)
        i += 1
    return out


def _dispatch(args: argparse.Namespace) -> int:
    """Check the parsed arguments, run the command's handler; a DesmonError is one line.
    A user's deployer (``--deployer FILE.py:NAME``) runs in a worker process of its own
    (:mod:`desmon.verify.isolation`), started as the option is resolved."""
    from desmon.deployment.guard import EXIT_CRASHED, MAX_COMMANDS, MAX_REACTION_SECONDS, DeployerFault, Guard

    try:
        # this command's guard around the deployer: its limits, handed to every engine it runs
        deadline = (args.max_reaction_seconds or MAX_REACTION_SECONDS) if hasattr(args, "max_reaction_seconds") else None
        args.guard = Guard(getattr(args, "max_commands", None) or MAX_COMMANDS, deadline)
        preflight(args)  # inputs, numbers, windows and output paths, before any long work (then the deployer's import)
        run_of(args)  # this command's run context: its guard and its planned outputs (each engine adds its own memoised checks)
        with args.guard.deadline(), contextlib.redirect_stdout(WholeWrites(sys.stdout)):  # (printed whole under the timer)
            return int(args.handler(args))
    except DeployerFault as exc:
        # (SimPy re-raises a process's exception as a copy caused by the original)
        if exc.initial or getattr(exc.__cause__, "initial", False):  # the deployer cannot run at all: bad input
            print(f"desmon: error: {one_line(exc)}", file=sys.stderr)
            return EXIT_USAGE
        print(f"desmon: CRASHED: {one_line(exc)}", file=sys.stderr)  # it failed in a state the run reached
        return EXIT_CRASHED
    except DesmonError as exc:
        print(f"desmon: error: {one_line(exc)}", file=sys.stderr)
        return EXIT_USAGE
    except BrokenPipeError:  # the reader of the output went away (desmon ... | head): end quietly, as a pipe's writer does
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # (the interpreter's final flush then has nowhere to fail)
        return 128 + 13  # SIGPIPE's exit status
    except OSError as exc:  # an output file that cannot be written, a directory that does not exist
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"desmon: error: {one_line(f'{where}cannot read or write: {exc.strerror or exc}; check the path')}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        print("desmon: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
