"""``desmon explain``: why each platform is accepted or rejected for a perception graph at a moment."""

from __future__ import annotations

import argparse

from desmon.cli.common import EXIT_OK, Subparsers, deployer_arg, load_scripted, resolve_times, scenario_arg, run_of

__all__ = ["add_parser", "run"]


def add_parser(sub: Subparsers) -> None:
    p = sub.add_parser("explain", help="why each platform is accepted or rejected for a perception graph")
    scenario_arg(p)
    p.add_argument("graph", help="perception graph, e.g. combined_slip_detector")
    p.add_argument("--at", default=None, help="seconds or a timeline label such as t1 (default: the timeline's end)")
    deployer_arg(p)
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    from dataclasses import replace

    from desmon.deployment.validity import acceptable_platforms
    from desmon.errors import QueryError
    from desmon.repository.query import RepositoryQuery
    from desmon.sim.replay import replay

    scenario = load_scripted(args)
    if "," in (args.at or ""):
        raise QueryError(f"--at {args.at!r}: explain answers for one moment; give one time or label")
    [(when, _at, steps)] = resolve_times(scenario, args.at)
    if scenario.model.spec(args.graph) is None:
        known = ", ".join(s.graph for s in scenario.model.specs)
        graphs = [g.name for g in scenario.model.graphs]
        what = (f"perception graph {args.graph!r} has no deployment specification" if args.graph in graphs
                else f"no deployment specification for {args.graph!r}")
        listing = f"the graphs with one: {known}" if known else "the scenario gives none (robot.depsl.deployment_specification(...))"
        raise QueryError(f"{args.scenario}: {what}, so nothing to explain; {listing}")
    timeline = scenario.timeline[:steps]  # (a label's moment: not a later event of the same time)
    result = replay(replace(scenario, timeline=timeline), args.deployer, run=run_of(args))
    validity = acceptable_platforms(RepositoryQuery(result.repo), args.graph)
    fixed = scenario.model.spec(args.graph).fixed_platform  # type: ignore[union-attr]
    print(f"{args.graph} at {when} ({args.deployer.name} deployer):")
    if fixed is not None:
        print(f"fixed deployment: only its EXECUTABLE_ON platform {fixed} is considered")
    print(validity.explain())
    return EXIT_OK
