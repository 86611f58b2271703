"""``desmon sweep-plot``: draw a sweep table (docs/sweeps.md): a figure against a parameter
(mean, min-max and the mean's 95 % interval over the seeds), or a Pareto front. pandas is imported when it runs.
"""

from __future__ import annotations

import argparse

from desmon.cli.common import EXIT_OK, Subparsers
from desmon.cli.options import add_input, add_output

__all__ = ["add_parser", "run", "TABLE_FILE"]

TABLE_FILE = ("sweep table", "write one with: desmon sweep SCENARIO -p NAME=V1,V2 -o results.parquet")


def add_parser(sub: Subparsers) -> None:
    p = sub.add_parser("sweep-plot", help="draw a sweep table: a figure vs a parameter (mean, min-max and 95 %% interval over seeds), or a Pareto front")
    add_input(p, "table", TABLE_FILE, help="table written by desmon sweep (.parquet or .csv)")
    p.add_argument("-x", default=None, metavar="COLUMN", help="the parameter on the x axis, e.g. hand_memory")
    p.add_argument("-y", required=True, metavar="COLUMN", help="the figure on the y axis, e.g. exposure_s")
    p.add_argument("--pareto", default=None, metavar="COST",
                   help="instead of -x: each point's mean -y against this cost column (e.g. hand_memory), with the Pareto front")
    p.add_argument("--better", default=None, choices=("lower", "higher"),
                   help="with --pareto: which way -y is better (default: desmon's own figures say: a lower exposure_s, a "
                        "higher tp_rate_force; another column needs it)")
    p.add_argument("--log-x", action="store_true",
                   help="the x axis on a log scale, for values that span decades (an MTTF of 900 s to 4 h, say)")
    add_output(p, "-o", "--output", suffixes=(".png",), default="sweep.png", metavar="FILE.png", help="PNG file")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    from desmon.sweep.plot import plot_sweep
    from desmon.sweep.runner import require_extra

    modules = ("pandas", "pyarrow") if args.table.lower().endswith(".parquet") else ("pandas",)
    require_extra("sweep-plot", modules)
    plot_sweep(args.table, args.output, x=args.x, y=args.y, pareto=args.pareto, log_x=args.log_x, better=args.better)
    print(f"wrote {args.output}")
    return EXIT_OK
