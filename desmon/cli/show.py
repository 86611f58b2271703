"""``desmon show``: the repository graph at one or more moments of a scenario's timeline,
as png (side by side), dot, graphml, json or cypher."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from desmon.cli.common import EXIT_OK, Subparsers, deployer_arg, load_scripted, resolve_times, scenario_arg, run_of
from desmon.cli.options import add_output

__all__ = ["add_parser", "run", "SHOW_FORMATS"]

#: ``show --format`` -> the file suffixes it writes (the first is the usual one).
SHOW_FORMATS = {"png": (".png",), "dot": (".dot", ".gv"), "graphml": (".graphml",), "json": (".json",), "cypher": (".cypher", ".cql")}


def add_parser(sub: Subparsers) -> None:
    p = sub.add_parser("show", help="the repository graph at a time, as png, dot, graphml, json or cypher")
    scenario_arg(p)
    p.add_argument("--at", default=None, help="seconds or timeline labels, comma-separated (e.g. t0,t1,t2,t3)")
    p.add_argument(
        "--format", default=None, choices=list(SHOW_FORMATS),
        help="what to write; when not given: the suffix of -o (.png .dot .graphml .json .cypher), else png",
    )
    add_output(
        p, "-o", "--output", formats=SHOW_FORMATS, default_format="png", default=None,
        help="output file, its suffix matching --format (text formats default to stdout)",
    )
    deployer_arg(p)
    p.set_defaults(handler=run)


def _snapshots(scenario: Any, result: Any, moments: list[tuple[str, float, int]]) -> list[tuple[str, Any]]:
    """(title, repository snapshot) of each moment: the context then, and the errors raised
    then (by the moment's steps of its time: a label's, not a later event's of the same time)."""
    snaps = []
    for title, t, steps in moments:
        snap = result.graph_after(steps)
        ctx = [d["name"] for n, d in snap.nodes(data=True) if d.get("label") == "Context" and any(True for _ in snap.in_edges(n))]
        errors = [f"{e.kind}: {e.graph}" for step in result.steps[:steps] if step.time == t for e in step.errors]
        head = f"{scenario.name} {title}" + (f"  context: {ctx[0]}" if ctx else "")
        snaps.append((head + "".join(f"\nerror raised: {e}" for e in errors), snap))
    return snaps


def run(args: argparse.Namespace) -> int:
    import json

    from desmon.errors import ScenarioError
    from desmon.paths import check_output_file, replacing
    from desmon.repository.export import graph_to_cypher, graph_to_dot
    from desmon.repository.store import graph_to_graphml, graph_to_json
    from desmon.sim.replay import replay

    scenario = load_scripted(args)
    moments = resolve_times(scenario, args.at)
    result = replay(scenario, args.deployer, run=run_of(args))
    snaps = _snapshots(scenario, result, moments)
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
