"""Text exports of repository snapshots: Graphviz DOT and a Cypher script.

The Cypher script recreates the snapshot in a graph database (Neo4j): one ``CREATE`` per
node with its label and scalar properties, then one ``MATCH ... CREATE`` per edge.
JSON and GraphML live in :mod:`desmon.repository.store`.
"""

from __future__ import annotations

import json
from typing import Any

import networkx as nx

from desmon.model.checks import seconds_text, visible
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


def _dot_quote(*lines: str) -> str:
    """``lines`` as one DOT string, a \\n line break between them: a backslash or a
    character that is not printable in a line is escaped, a newline is a \\n line break
    and a double quote becomes a single one, so no name can end the string or the file."""
    return '"' + "\\n".join(visible(str(line)).replace("\\", "\\\\").replace('"', "'").replace("\n", "\\n") for line in lines) + '"'


def graph_to_dot(g: nx.MultiDiGraph, title: str = "") -> str:
    """A Graphviz DOT rendering of a snapshot (nodes shaped by label, deployment edges styled)."""
    lines = ["digraph repository {", "  rankdir=LR;", '  node [fontname="Helvetica", fontsize=10];',
             '  edge [fontname="Helvetica", fontsize=8];']
    if title:
        lines.append(f"  label={_dot_quote(title)}; labelloc=t;")
    for n, d in sorted(g.nodes(data=True)):
        label = d.get("label", "")
        text = _dot_quote(str(label), str(d.get("description") or d.get("name", n)))
        lines.append(f"  {_dot_quote(n)} [shape={_SHAPES.get(label, 'box')}, label={text}];")
    for s, t, _k, d in sorted(g.edges(keys=True, data=True), key=lambda e: (e[0], e[1], str(e[2]))):
        label = d.get("label", "")
        extra = [f"{a}={seconds_text(d[a])}" for a in ("start", "stop") if isinstance(d.get(a), (int, float))]
        style = _EDGE_STYLE.get(label, 'color="#444444"')
        lines.append(f"  {_dot_quote(s)} -> {_dot_quote(t)} [label={_dot_quote(str(label), *extra)}, {style}];")
    lines.append("}")
    return "\n".join(lines) + "\n"


def _cypher_value(v: Any) -> str:
    """A Cypher literal: a string with its backslashes and quotes escaped, and every
    character that is not printable (but a newline and a tab) as a \\u escape."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    text = str(v).replace("\\", "\\\\").replace("'", "\\'")
    if not text.isprintable():
        text = "".join(ch if ch.isprintable() or ch in "\n\t" else _cypher_escape(ch) for ch in text)
    return "'" + text + "'"


def _cypher_escape(ch: str) -> str:
    return f"\\u{ord(ch):04x}" if ord(ch) <= 0xFFFF else f"\\U{ord(ch):08x}"


def _cypher_name(name: object) -> str:
    """A Cypher name (a label, a relationship type, a property key) in backticks, a backtick inside doubled."""
    return "`" + visible(str(name)).replace("`", "``") + "`"


def _cypher_map(props: dict[str, Any]) -> str:
    return "{" + ", ".join(f"{_cypher_name(k)}: {_cypher_value(v)}" for k, v in props.items()) + "}"


def graph_to_cypher(g: nx.MultiDiGraph) -> str:
    """A Cypher script that recreates the snapshot (nodes keyed by their ``id`` property)."""
    lines = ["// desmon repository snapshot; load with: cypher-shell < this-file", "MATCH (n {desmon: true}) DETACH DELETE n;"]
    for n, d in sorted(g.nodes(data=True)):
        props = {"id": n, "desmon": True, **_props(d)}
        lines.append(f"CREATE (:{_cypher_name(d.get('label', 'Node'))} {_cypher_map(props)});")
    for s, t, _k, d in sorted(g.edges(keys=True, data=True), key=lambda e: (e[0], e[1], str(e[2]))):
        props = _props(d)
        rel = f"[:{_cypher_name(d.get('label', 'RELATED'))}" + (f" {_cypher_map(props)}" if props else "") + "]"
        lines.append(f"MATCH (a {{id: {_cypher_value(s)}}}), (b {{id: {_cypher_value(t)}}}) CREATE (a)-{rel}->(b);")
    return "\n".join(lines) + "\n"
