"""``desmon replay``: a scenario's scripted timeline through the deployment core (no signals)."""

from __future__ import annotations

import argparse

from desmon.cli.common import EXIT_OK, EXIT_VIOLATED, Subparsers, deployer_arg, load_scripted, scenario_arg, run_of

__all__ = ["add_parser", "run"]


def add_parser(sub: Subparsers) -> None:
    p = sub.add_parser("replay", help="replay a scenario's scripted timeline through the deployment core (no signals)")
    scenario_arg(p)
    deployer_arg(p)
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    from desmon.sim.replay import format_replay, replay

    scenario = load_scripted(args)
    result = replay(scenario, args.deployer, run=run_of(args))
    print(format_replay(result), end="")
    return EXIT_VIOLATED if result.violations else EXIT_OK
