"""``desmon fuzz``: hypothesis-generated failure sequences through the deployment core, shrunk on failure.

Ctrl-C ends it with its partial result, exit 130, without a traceback.
"""

from __future__ import annotations

import argparse
import sys

from desmon.cli.common import Subparsers, deployer_arg, load_scenario_of, scenario_arg, warn_uncovered
from desmon.cli.options import bounded_count, non_negative_int
from desmon.errors import CheckerError

__all__ = ["add_parser", "run", "MAX_EXAMPLES"]

#: the most sequences one fuzz run generates (a million take hours already)
MAX_EXAMPLES = 1_000_000


def add_parser(sub: Subparsers) -> None:
    p = sub.add_parser("fuzz", help="hypothesis-generated failure sequences, shrunk on failure")
    scenario_arg(p)
    deployer_arg(p)
    p.add_argument("--examples", type=bounded_count(MAX_EXAMPLES, "sequences"), default=200,
                   help=f"failure sequences to generate (at most {MAX_EXAMPLES:,})")
    p.add_argument("--seed", type=non_negative_int, default=0, help="hypothesis seed (the same seed draws the same sequences)")
    p.add_argument("--together", action="store_true",
                   help="also draw two changes answered by one reaction (the scenario's Bounds(together=True))")
    p.add_argument("--no-progress", action="store_true")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    from desmon.progress import drawn_on
    from desmon.verify.fuzz import fuzz, scratch_hypothesis_home

    if args.examples <= 0:
        raise CheckerError(f"--examples must be positive, got {args.examples}")
    scenario = load_scenario_of(args)
    with scratch_hypothesis_home():
        progress = not args.no_progress and drawn_on(sys.stderr)
        outcome = fuzz(scenario, args.deployer, examples=args.examples, seed=args.seed, progress=progress, guard=args.guard)
    print(outcome.text, end="")
    warn_uncovered(scenario)  # as verify does: a risky action no rule covers is unmonitored whatever the sequence
    return outcome.exit_code
