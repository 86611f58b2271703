"""``desmon plot``: draw the timeline of a run's JSON Lines trace."""

from __future__ import annotations

import argparse

from desmon.cli.common import EXIT_OK, Subparsers, draw_trace
from desmon.cli.options import add_input, add_output, add_window
from desmon.paths import TRACE_FILE

__all__ = ["add_parser", "run"]


def add_parser(sub: Subparsers) -> None:
    p = sub.add_parser("plot", help="draw the timeline of a run's JSON Lines trace")
    add_input(p, "trace", TRACE_FILE, help="trace file written by desmon run --trace")
    add_output(p, "-o", "--output", suffixes=(".png",), default="timeline.png", metavar="FILE.png", help="PNG file")
    add_window(p, ("--from", "start"), ("--to", "end"))
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    draw_trace(args.trace, args.output, args.start, args.end)
    return EXIT_OK
