"""Text exports of repository snapshots: Graphviz DOT and a Cypher script.

The Cypher script recreates the snapshot in a graph database (Neo4j): one ``CREATE`` per
node with its label and scalar properties, then one ``MATCH ... CREATE`` per edge.
JSON and GraphML live in :mod:`desmon.repository.store`.
"""

from __future__ import annotations

import json
from typing import Any

import networkx as nx

from desmon.repository.store import OBJECT_ATTRS, jsonable

__all__ = ["graph_to_dot", "graph_to_cypher", "FORMATS"]

FORMATS = ("json", "graphml", "dot", "cypher", "png")

_SHAPES = {
    "Platform": "box3d",
    "Device": "ellipse",
    "PerceptionGraph": "component",
    "Deployment": "note",
    "Requirement": "box",
    "Context": "diamond",
    "Robot": "house",
}
_EDGE_STYLE = {
    "DEPLOYED_ON": 'color="#1b7837", penwidth=2.5',
    "DEPLOYMENT_HISTORY": 'color="#888888", style=dashed',
    "EXECUTABLE_ON": 'color="#762a83", style=bold',
    "HAS_DEVICE": 'color="#2166ac"',
}


def _props(data: dict[str, Any]) -> dict[str, Any]:
    out = {}
    for k, v in sorted(data.items()):
        if k in OBJECT_ATTRS or k == "label":
            continue
        v = jsonable(v)
        out[k] = v if isinstance(v, (str, int, float, bool)) else json.dumps(v, sort_keys=True)
    return out


def _dot_quote(text: str) -> str:
    """Quote for DOT; backslash sequences such as the \\n line break are kept."""
    return '"' + text.replace('"', "'") + '"'


def graph_to_dot(g: nx.MultiDiGraph, title: str = "") -> str:
    """A Graphviz DOT rendering of a snapshot (nodes shaped by label, deployment edges styled)."""
    lines = ["digraph repository {", "  rankdir=LR;", '  node [fontname="Helvetica", fontsize=10];',
             '  edge [fontname="Helvetica", fontsize=8];']
    if title:
        lines.append(f"  label={_dot_quote(title)}; labelloc=t;")
    for n, d in sorted(g.nodes(data=True)):
        label = d.get("label", "")
        text = f"{label}\\n{d.get('description') or d.get('name', n)}"
        lines.append(f"  {_dot_quote(n)} [shape={_SHAPES.get(label, 'box')}, label={_dot_quote(text)}];")
    for s, t, _k, d in sorted(g.edges(keys=True, data=True), key=lambda e: (e[0], e[1], str(e[2]))):
        label = d.get("label", "")
        extra = "".join(f"\\n{a}={d[a]:g}" for a in ("start", "stop") if isinstance(d.get(a), (int, float)))
        style = _EDGE_STYLE.get(label, 'color="#444444"')
        lines.append(f"  {_dot_quote(s)} -> {_dot_quote(t)} [label={_dot_quote(label + extra)}, {style}];")
    lines.append("}")
    return "\n".join(lines) + "\n"


def _cypher_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    return "'" + str(v).replace("\\", "\\\\").replace("'", "\\'") + "'"


def _cypher_map(props: dict[str, Any]) -> str:
    return "{" + ", ".join(f"`{k}`: {_cypher_value(v)}" for k, v in props.items()) + "}"


def graph_to_cypher(g: nx.MultiDiGraph) -> str:
    """A Cypher script that recreates the snapshot (nodes keyed by their ``id`` property)."""
    lines = ["// desmon repository snapshot; load with: cypher-shell < this-file", "MATCH (n {desmon: true}) DETACH DELETE n;"]
    for n, d in sorted(g.nodes(data=True)):
        props = {"id": n, "desmon": True, **_props(d)}
        lines.append(f"CREATE (:`{d.get('label', 'Node')}` {_cypher_map(props)});")
    for s, t, _k, d in sorted(g.edges(keys=True, data=True), key=lambda e: (e[0], e[1], str(e[2]))):
        props = _props(d)
        rel = f"[:`{d.get('label', 'RELATED')}`" + (f" {_cypher_map(props)}" if props else "") + "]"
        lines.append(f"MATCH (a {{id: {_cypher_value(s)}}}), (b {{id: {_cypher_value(t)}}}) CREATE (a)-{rel}->(b);")
    return "\n".join(lines) + "\n"
