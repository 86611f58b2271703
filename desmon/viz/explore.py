"""The explorer's page: one self-contained HTML file to step through a run (``desmon explore``).

A *frame* is what a student sees at one step of the scripted replay (``desmon replay``,
t0..t3 of the paper's Fig. 5) or of a counterexample (``desmon verify``): the event, what
the deployer did, the errors raised and standing, the invariants, the repository snapshot
and the reasons ``desmon explain`` gives for every perception graph on every platform.
:func:`capture_reasons` asks :func:`~desmon.deployment.validity.acceptable_platforms`
for those reasons on the live repository of that step (nothing here re-states a rule);
:func:`render_page` draws the frames.

The page has no server and fetches nothing: CSS, JS and one SVG per step are inline. The
graph layout is computed here, deterministically (columns PerceptionGraph | Deployment |
Platform | Device under a row of Robot and Context nodes, each column in the order the
nodes entered the repository, devices grouped by their platform), from the union of
every frame's nodes, so only edges and node states change from step to step. The same
frames give the same bytes: no clock, no random ids, every set sorted.
"""

from __future__ import annotations

import html
from dataclasses import dataclass
from typing import Any, Iterable, Sequence

import networkx as nx

from desmon.model.checks import seconds_text, visible
from desmon.repository import labels as L

__all__ = ["Reasons", "Frame", "capture_reasons", "render_page", "FIG5_EDGES", "COLUMNS"]

#: the node columns, left to right (Robot and Context nodes are drawn in a row above them)
COLUMNS = (L.PERCEPTION_GRAPH, L.DEPLOYMENT, L.PLATFORM, L.DEVICE)
#: the edges drawn (REQUIRES is written into the Deployment box as its requirement lines)
FIG5_EDGES = (L.HAS_DEVICE, L.DEPLOYED_ON, L.DEPLOYMENT_HISTORY, L.EXECUTABLE_ON, L.RESOLVES, L.IN_CONTEXT)

EDGE_COLOR = {
    L.DEPLOYED_ON: "#1b7837", L.DEPLOYMENT_HISTORY: "#8a8a8a", L.EXECUTABLE_ON: "#762a83",
    L.HAS_DEVICE: "#2166ac", L.RESOLVES: "#b35806", L.IN_CONTEXT: "#c51b7d",
}
NODE_FILL = {
    L.PLATFORM: "#fdb863", L.DEVICE: "#92c5de", L.PERCEPTION_GRAPH: "#fee0b6", L.DEPLOYMENT: "#a6dba0",
    L.CONTEXT: "#f1b6da", L.ROBOT: "#d8daeb",
}
#: one colour per platform in the timeline (cycled)
PLATFORM_PALETTE = ("#e08214", "#2166ac", "#1b7837", "#762a83", "#b2182b", "#35978f", "#8c510a", "#4d4d4d")


@dataclass(frozen=True)
class Reasons:
    """What ``desmon explain GRAPH`` says at one step, and the same per platform."""

    graph: str
    fixed: str | None  # the EXECUTABLE_ON platform of a fixed deployment
    acceptable: tuple[str, ...]  # best first
    scores: tuple[float, ...]  # aligned with acceptable (empty without preferences)
    failures: tuple[tuple[str, tuple[str, ...]], ...]  # rejected platform -> str(Failure) lines
    text: str  # Validity.explain(), verbatim


@dataclass(frozen=True)
class Frame:
    """One step of the explorer."""

    key: str  # short name: "t1", or the step number of a counterexample
    title: str  # e.g. "t1 t=5s  action move_base"
    event: str  # the event, or "initial state"
    time: float | None  # seconds (scripted replay), None for counterexample steps
    commands: tuple[str, ...]  # what the deployer did, in order ("start x on p: ok")
    raised: tuple[tuple[str, str], ...]  # (headline, detail) of each error raised at this step
    standing: tuple[tuple[str, str], ...]  # (graph, text) of each error standing after the step
    violations: tuple[tuple[str, str], ...]  # (invariant, message) violated at this step
    notes: tuple[str, ...]  # anything else to say (the checker's failing starts, a divergence)
    graph: nx.MultiDiGraph  # the repository snapshot after the step
    reasons: tuple[Reasons, ...]  # one per perception graph with a deployment specification


def capture_reasons(query: Any, graphs: Iterable[str]) -> tuple[Reasons, ...]:
    """``desmon explain``'s answer for each of ``graphs`` on the live repository behind
    ``query`` (a :class:`~desmon.repository.query.RepositoryQuery`), as it is now."""
    from desmon.deployment.validity import acceptable_platforms

    out = []
    for graph in graphs:
        validity = acceptable_platforms(query, graph)
        spec = query.deployment_information(graph)
        out.append(
            Reasons(
                graph=graph,
                fixed=getattr(spec, "fixed_platform", None),
                acceptable=tuple(validity.acceptable),
                scores=tuple(validity.scores),
                failures=tuple((name, tuple(str(f) for f in fails)) for name, fails in validity.rejected),
                text=validity.explain(),
            )
        )
    return tuple(out)


# --------------------------------------------------------------------------- text helpers
def _e(text: object) -> str:
    """``text`` for the page: HTML-escaped, a character that is not printable (a NUL, a
    right-to-left override) written as its escape, so no name is markup or hides."""
    return html.escape(visible(str(text)), quote=True)


def _n(x: float) -> str:
    """A coordinate, written the same way every time."""
    return f"{x:.1f}".rstrip("0").rstrip(".") if x != int(x) else str(int(x))


def _width(text: str, size: float) -> float:
    """An estimate of the rendered width of ``text`` in a sans-serif font of ``size`` px."""
    return len(text) * size * 0.58


def _name(g: nx.MultiDiGraph, n: str) -> str:
    return str(g.nodes[n].get("name", n.split(":", 1)[-1]))


# --------------------------------------------------------------------------- node contents
def _node_lines(g: nx.MultiDiGraph, n: str) -> tuple[str, list[str], list[str]]:
    """(title, detail lines, state flags) of node ``n`` in snapshot ``g``."""
    d = g.nodes[n]
    label = d.get("label")
    name = _name(g, n)
    lines: list[str] = []
    flags: list[str] = []
    if label == L.PLATFORM:
        caps = d.get("capacities") or {}
        load = d.get("load") or {}
        for resource in sorted(caps):
            used = load.get(resource)
            lines.append(f"{resource} {caps[resource]:g}" + (f", load {used:g}" if used else ""))
        if d.get("up") is False:
            flags.append("down")
    elif label == L.DEVICE:
        lines.append(str(d.get("kind", "")))
        if d.get("working") is False:
            flags.append("failed")
    elif label == L.PERCEPTION_GRAPH:
        reads = d.get("reads") or ()
        if reads:
            lines.append("reads " + ", ".join(map(str, reads)))
    elif label == L.DEPLOYMENT:
        spec = d.get("spec")  # (the current specification lists them in the order every reader sees)
        place = {r: i for i, r in enumerate(getattr(spec, "requirements", ()))}
        reqs = sorted(
            ((place.get(g.nodes[t].get("requirement"), len(place)), g.nodes[t].get("order", 0)), str(g.nodes[t].get("description", t)))
            for _s, t, ed in g.out_edges(n, data=True) if ed.get("label") == L.REQUIRES and t in g
        )
        lines.extend(text for _o, text in reqs)
    return name, lines, flags


# --------------------------------------------------------------------------- layout
@dataclass(frozen=True)
class _Box:
    x: float  # left
    y: float  # top
    w: float
    h: float

    @property
    def cx(self) -> float:
        return self.x + self.w / 2

    @property
    def cy(self) -> float:
        return self.y + self.h / 2


TITLE_PX, LINE_PX = 12.5, 10.5
ROW_GAP = 12
TOP_ROW_Y = 8
CONTEXT_ROW_Y = 62
COLUMN_TOP = 132
#: horizontal gap after each column (room for the edge labels between Deployment and Platform)
COLUMN_GAP = {L.PERCEPTION_GRAPH: 44, L.DEPLOYMENT: 150, L.PLATFORM: 70, L.DEVICE: 0}


def _union(frames: Sequence[Frame]) -> nx.MultiDiGraph:
    """Every node that any frame shows, with its data from the last frame that shows it."""
    full = nx.MultiDiGraph()
    for f in frames:
        for n, d in f.graph.nodes(data=True):
            full.add_node(n, **d)
        for s, t, d in f.graph.edges(data=True):
            label = d.get("label")
            if label in (L.HAS_DEVICE, L.RESOLVES, L.REQUIRES) and not any(
                e.get("label") == label for e in (full.get_edge_data(s, t) or {}).values()
            ):
                full.add_edge(s, t, **d)
    return full


def _ordered(full: nx.MultiDiGraph, label: str) -> list[str]:
    return [n for _o, n in sorted((d.get("order", 0), n) for n, d in full.nodes(data=True) if d.get("label") == label)]


def layout(frames: Sequence[Frame]) -> tuple[dict[str, _Box], dict[str, float], float, float]:
    """Boxes of every node of every frame, the x of each column's heading, and the
    drawing's width and height. Deterministic: depends on the frames' graphs only."""
    full = _union(frames)
    columns = {label: _ordered(full, label) for label in COLUMNS}
    platforms = columns[L.PLATFORM]

    def owner(dev: str) -> int:  # devices grouped under the platform they hang on
        device = full.nodes[dev].get("device")
        name = getattr(device, "platform", None)
        owners = [platforms.index(s) for s, _t, d in full.in_edges(dev, data=True) if d.get("label") == L.HAS_DEVICE and s in platforms]
        if name is not None and f"{L.PLATFORM}:{name}" in platforms:
            return platforms.index(f"{L.PLATFORM}:{name}")
        return min(owners) if owners else len(platforms)

    columns[L.DEVICE] = sorted(columns[L.DEVICE], key=lambda n: (owner(n), full.nodes[n].get("order", 0), n))
    deployments = columns[L.DEPLOYMENT]

    def resolver(pg: str) -> int:
        ds = [deployments.index(s) for s, _t, d in full.in_edges(pg, data=True) if d.get("label") == L.RESOLVES and s in deployments]
        return min(ds) if ds else len(deployments)

    columns[L.PERCEPTION_GRAPH] = sorted(columns[L.PERCEPTION_GRAPH], key=lambda n: (resolver(n), full.nodes[n].get("order", 0), n))

    sizes: dict[str, tuple[float, float]] = {}
    for n in full.nodes:
        if full.nodes[n].get("label") not in (*COLUMNS, L.CONTEXT, L.ROBOT):
            continue
        title, lines, flags = _node_lines(full, n)
        head = title + (" (failed)" if "failed" in flags else "") + (" (down)" if "down" in flags else "")
        w = max([_width(head, TITLE_PX)] + [_width(t, LINE_PX) for t in lines]) + 18
        h = 22 + 13 * len(lines)
        sizes[n] = (w, h)

    boxes: dict[str, _Box] = {}
    heads: dict[str, float] = {}
    x = 16.0
    heights = []
    for label in COLUMNS:
        nodes = columns[label]
        cw = max([sizes[n][0] for n in nodes] + [_width(label, 11) + 10])
        heads[label] = x + cw / 2
        y = float(COLUMN_TOP)
        for n in nodes:
            w, h = sizes[n]
            boxes[n] = _Box(x + (cw - w) / 2, y, w, h)
            y += h + ROW_GAP
        heights.append(y)
        x += cw + COLUMN_GAP[label]
    width = x + 16
    # the top rows: the robot, and under it the row of its contexts, from the second column on
    robots, contexts = _ordered(full, L.ROBOT), _ordered(full, L.CONTEXT)
    cx = heads[L.DEPLOYMENT] - sizes[columns[L.DEPLOYMENT][0]][0] / 2 if columns[L.DEPLOYMENT] else 16.0
    row_start = cx
    for n in contexts:
        w, h = sizes[n]
        boxes[n] = _Box(cx, CONTEXT_ROW_Y, w, h)
        cx += w + 14
    middle = (row_start + cx - 14) / 2 if contexts else row_start
    rw = sum(sizes[n][0] + 14 for n in robots) - 14
    rx = max(16.0, middle - rw / 2)
    for n in robots:
        w, h = sizes[n]
        boxes[n] = _Box(rx, TOP_ROW_Y, w, h)
        rx += w + 14
    width = max(width, cx + 16, rx + 16)
    height = max(heights) + 8
    return boxes, heads, width, height


# --------------------------------------------------------------------------- SVG of one frame
#: an edge of a frame, as the next frame finds it again: source, label, target, its start
#: with every digit, and which of the edges alike it is (two history records of one
#: deployment started at the same instant are two edges)
EdgeId = tuple[str, str, str, str, int]


def _edges(g: nx.MultiDiGraph) -> dict[EdgeId, dict[str, Any]]:
    out: dict[EdgeId, dict[str, Any]] = {}
    for s, t, d in g.edges(data=True):
        if d.get("label") in FIG5_EDGES:
            start = d.get("start")
            alike = (s, str(d.get("label")), t, "" if start is None else repr(start))
            n = 0
            while (*alike, n) in out:
                n += 1
            out[(*alike, n)] = d
    return out


def _node_state(g: nx.MultiDiGraph, n: str) -> tuple:  # type: ignore[type-arg]
    """What the node's box shows (a changed load, a failed device, new requirements ...)."""
    title, lines, flags = _node_lines(g, n)
    return title, tuple(lines), tuple(flags)


def _anchor(b: _Box, other: _Box) -> tuple[float, float]:
    """Where an edge towards ``other`` leaves box ``b``: a side, or top/bottom in the same column."""
    if other.x >= b.x + b.w:
        return b.x + b.w, b.cy
    if other.x + other.w <= b.x:
        return b.x, b.cy
    return b.cx, (b.y if other.cy < b.cy else b.y + b.h)


def _bend_of(label: str, rank: int) -> float:
    if label == L.DEPLOYED_ON:
        return 0.0
    if label == L.EXECUTABLE_ON:
        return -34.0
    if label == L.DEPLOYMENT_HISTORY:
        return 34.0 + 22.0 * rank
    return 0.0


@dataclass(frozen=True)
class _Label:
    """An edge label: centred at (x, y) where its edge passes, one or two lines."""

    x: float
    y: float
    lines: tuple[str, ...]
    color: str
    cls: str

    @property
    def w(self) -> float:
        return max(_width(t, 9.5) for t in self.lines) + 8

    @property
    def h(self) -> float:
        return 13 * len(self.lines) + 3


def _overlaps(x: float, y: float, w: float, h: float, other: tuple[float, float, float, float]) -> bool:
    ox, oy, ow, oh = other
    return x < ox + ow and ox < x + w and y < oy + oh and oy < y + h


def _place_labels(labels: Sequence[_Label], obstacles: Sequence[_Box]) -> list[tuple[_Label, float]]:
    """Each label with the vertical shift that keeps it clear of the labels placed before it
    and of every node box: the smallest of 0, +4, -4, +8, ... px that is clear (0 if none
    within 96 px). Deterministic: labels are taken in the order given."""
    placed: list[tuple[float, float, float, float]] = []
    boxes = [(b.x, b.y, b.w, b.h) for b in obstacles]
    out = []
    for lab in labels:
        w, h = lab.w, lab.h
        x = lab.x - w / 2
        shift = 0.0
        for step in range(49):
            dy = (step + 1) // 2 * 4.0 * (1 if step % 2 else -1)
            top = lab.y - h / 2 + dy
            if not any(_overlaps(x, top, w, h, r) for r in (*placed, *boxes)):
                shift = dy
                break
        placed.append((x, lab.y - h / 2 + shift, w, h))
        out.append((lab, shift))
    return out


def _label_svg(lab: _Label, shift: float) -> str:
    """A label on a white plate; moved off its edge, with a thin leader line back to it."""
    w, h = lab.w, lab.h
    top = lab.y - h / 2 + shift
    out = [f'<g class="{lab.cls}">']
    if abs(shift) > h / 2:
        edge_y = top + (h if shift < 0 else 0)
        out.append(f'<line x1="{_n(lab.x)}" y1="{_n(lab.y)}" x2="{_n(lab.x)}" y2="{_n(edge_y)}" stroke="{lab.color}" stroke-width="0.6" stroke-dasharray="1 2"/>')
    out.append(f'<rect x="{_n(lab.x - w / 2)}" y="{_n(top)}" width="{_n(w)}" height="{_n(h)}" rx="3" fill="white" '
               f'fill-opacity="0.94" stroke="{lab.color}" stroke-width="0.6"/>')
    for i, t in enumerate(lab.lines):
        out.append(f'<text x="{_n(lab.x)}" y="{_n(top + 11.5 + 13 * i)}" font-size="9.5" text-anchor="middle" fill="{lab.color}">{_e(t)}</text>')
    out.append("</g>")
    return "".join(out)


def _svg_edge(
    boxes: dict[str, _Box], key: EdgeId, d: dict[str, Any], change: str, rank: int, timed: bool = True
) -> tuple[str, "_Label | None"]:
    """The edge's SVG and its label (drawn over the nodes; None for none). Without ``timed``
    (a counterexample: its repository has no clock) the labels leave out start and stop."""
    s, label, t, _start, _nth = key
    a, b = boxes[s], boxes[t]
    x1, y1 = _anchor(a, b)
    x2, y2 = _anchor(b, a)
    color = EDGE_COLOR.get(label, "#555555")
    if label == L.IN_CONTEXT:  # the robot above -> a context of the row under it
        x1, y1 = a.cx, a.y + a.h
        x2, y2 = b.cx, b.y
        mx, my = (x1 + x2) / 2, (y1 + y2) / 2
    else:
        bend = _bend_of(label, rank)
        dx, dy = x2 - x1, y2 - y1
        length = max((dx * dx + dy * dy) ** 0.5, 1.0)
        mx, my = (x1 + x2) / 2 - dy / length * bend, (y1 + y2) / 2 + dx / length * bend
    dash = ' stroke-dasharray="6 4"' if label == L.DEPLOYMENT_HISTORY else ""
    width = {L.DEPLOYED_ON: 3.0, L.DEPLOYMENT_HISTORY: 1.8, L.EXECUTABLE_ON: 2.0}.get(label, 1.3)
    if change == "removed":
        color, dash, width = "#d73027", ' stroke-dasharray="2 4"', 1.6
    marker = "removed" if change == "removed" else label
    start, stop = (d.get(k) if timed else None for k in ("start", "stop"))
    times = "".join(f" {k}={seconds_text(d[k])}s" for k in ("start", "stop") if timed and isinstance(d.get(k), (int, float)))
    title = f"{s} -[{label}]-> {t}{times}" + {"added": " (new at this step)", "removed": " (removed at this step)"}.get(change, "")
    path = f"M{_n(x1)},{_n(y1)} Q{_n(mx)},{_n(my)} {_n(x2)},{_n(y2)}"
    attrs = f'data-label="{_e(label)}" data-source="{_e(s)}" data-target="{_e(t)}" data-change="{change}"'
    out = [f'<g class="edge {change}" {attrs}>', f"<title>{_e(title)}</title>"]
    if change == "added":
        out.append(f'<path d="{path}" fill="none" stroke="#ffe066" stroke-width="{_n(width + 6)}" stroke-linecap="round"/>')
    out.append(f'<path d="{path}" fill="none" stroke="{color}" stroke-width="{_n(width)}"{dash} marker-end="url(#arrow-{marker})"/>')
    out.append("</g>")
    # labels at the curve's middle; a removed edge's nearer its source, clear of a new edge's between the same boxes
    at = 0.3 if change == "removed" else 0.5
    lx = (1 - at) ** 2 * x1 + 2 * at * (1 - at) * mx + at * at * x2
    ly = (1 - at) ** 2 * y1 + 2 * at * (1 - at) * my + at * at * y2
    text: _Label | None = None
    if change == "removed" and label in (L.DEPLOYED_ON, L.HAS_DEVICE, L.EXECUTABLE_ON):
        text = _Label(lx, ly, (f"✗ {label}", "removed"), color, "edge-label removed")
    elif change != "removed" and label in (L.DEPLOYED_ON, L.DEPLOYMENT_HISTORY, L.EXECUTABLE_ON):
        if isinstance(start, (int, float)) and isinstance(stop, (int, float)):
            span = f"{seconds_text(start)}s – {seconds_text(stop)}s"
        elif isinstance(start, (int, float)):
            span = f"since {seconds_text(start)}s"
        else:
            span = ""
        text = _Label(lx, ly, (label, span) if span else (label,), color, "edge-label")
    return "".join(out), text


def _svg_node(g: nx.MultiDiGraph, n: str, box: _Box, changed: bool, active: bool, standing: bool) -> str:
    d = g.nodes[n]
    label = str(d.get("label"))
    title, lines, flags = _node_lines(g, n)
    fill, ink, stroke, sw = NODE_FILL.get(label, "#ffffff"), "#111111", "#555555", 1.0
    if "failed" in flags:
        fill, ink = "#e6e6e6", "#777777"
        title += " (failed)"
    if "down" in flags:
        fill, ink = "#444444", "#ffffff"
        title += " (down)"
    if label == L.DEPLOYMENT and not active:
        fill = "#e5f5e0"
    if standing:
        stroke, sw = "#d73027", 2.6
    elif changed:
        stroke, sw = "#f08c00", 2.6
    state = " ".join(flags + (["changed"] if changed else []) + (["active"] if active else []) + (["error"] if standing else []))
    out = [
        f'<g class="node" data-node="{_e(n)}" data-label="{_e(label)}" data-state="{_e(state)}">',
        f"<title>{_e(label)} {_e(_name(g, n))}</title>",
        f'<rect x="{_n(box.x)}" y="{_n(box.y)}" width="{_n(box.w)}" height="{_n(box.h)}" rx="{6 if label != L.CONTEXT else 13}" '
        f'fill="{fill}" stroke="{stroke}" stroke-width="{_n(sw)}"/>',
        f'<text x="{_n(box.cx)}" y="{_n(box.y + 15)}" font-size="{TITLE_PX}" font-weight="600" text-anchor="middle" fill="{ink}">{_e(title)}</text>',
    ]
    for i, line in enumerate(lines):
        out.append(f'<text x="{_n(box.cx)}" y="{_n(box.y + 29 + 13 * i)}" font-size="{LINE_PX}" text-anchor="middle" fill="{ink}">{_e(line)}</text>')
    out.append("</g>")
    return "".join(out)


def _markers() -> str:
    out = ["<defs>"]
    for name, color in (*sorted(EDGE_COLOR.items()), ("removed", "#d73027")):
        out.append(
            f'<marker id="arrow-{name}" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="7" markerHeight="7" orient="auto-start-reverse">'
            f'<path d="M0,0 L10,5 L0,10 z" fill="{color}"/></marker>'
        )
    out.append("</defs>")
    return "".join(out)


def _edge_layer(frame: Frame, prev: Frame | None, boxes: dict[str, _Box], timed: bool) -> tuple[list[str], list[_Label]]:
    """The edges of ``frame`` (those gone since ``prev`` drawn as removed, first), and their labels."""
    now = _edges(frame.graph)
    before = _edges(prev.graph) if prev is not None else {}
    items = [(k, d, "removed") for k, d in sorted(before.items()) if k not in now]
    items += [(k, d, "added" if prev is not None and k not in before else "kept") for k, d in sorted(now.items())]
    pairs: dict[tuple[str, str], int] = {}  # history edges so far between two boxes: each bends further
    out: list[str] = []
    labels: list[_Label] = []
    for key, d, change in items:
        s, label, t, _start, _nth = key
        if s not in boxes or t not in boxes:
            continue
        rank = pairs.get((s, t), 0) if label == L.DEPLOYMENT_HISTORY else 0
        if label == L.DEPLOYMENT_HISTORY:
            pairs[(s, t)] = rank + 1
        edge, text = _svg_edge(boxes, key, d, change, rank, timed)
        out.append(edge)
        if text is not None:
            labels.append(text)
    return out, labels


def _node_layer(frame: Frame, prev: Frame | None, boxes: dict[str, _Box]) -> list[str]:
    g = frame.graph
    active = {s for s, label, _t, _st, _nth in _edges(g) if label == L.DEPLOYED_ON}
    standing = {graph for graph, _text in frame.standing}
    out = []
    for n in sorted((n for n in g.nodes if n in boxes), key=lambda n: (boxes[n].y, boxes[n].x, n)):
        changed = prev is not None and n in prev.graph and _node_state(g, n) != _node_state(prev.graph, n)
        errored = g.nodes[n].get("label") == L.DEPLOYMENT and _name(g, n) in standing
        out.append(_svg_node(g, n, boxes[n], changed, n in active, errored))
    return out


def _svg_frame(frame: Frame, prev: Frame | None, boxes: dict[str, _Box], heads: dict[str, float], width: float, height: float) -> str:
    """The repository graph of one step: headings, edges, nodes, then the edge labels over them."""
    out = [
        f'<svg class="repo" xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {_n(width)} {_n(height)}" width="100%" style="max-width:{_n(width)}px" '
        f'font-family="DejaVu Sans, Arial, Helvetica, sans-serif" role="img" aria-label="repository graph at {_e(frame.title)}">',
        _markers(),
    ]
    for label, x in heads.items():
        out.append(f'<text x="{_n(x)}" y="{COLUMN_TOP - 12}" font-size="12" font-weight="700" text-anchor="middle" fill="#555">{_e(label)}</text>')
    edges, labels = _edge_layer(frame, prev, boxes, frame.time is not None)
    out += edges
    out += _node_layer(frame, prev, boxes)
    shown = [boxes[n] for n in sorted(frame.graph.nodes) if n in boxes]
    shown += [_Box(x - _width(label, 12) / 2, COLUMN_TOP - 24, _width(label, 12), 16) for label, x in heads.items()]
    out.extend(_label_svg(lab, dy) for lab, dy in _place_labels(labels, shown))  # over the nodes, clear of them
    out.append("</svg>")
    return "".join(out)


# --------------------------------------------------------------------------- timeline
def _deployed(g: nx.MultiDiGraph) -> dict[str, list[str]]:
    """Each deployed graph's platforms (more than one when an invariant is broken)."""
    out: dict[str, list[str]] = {}
    for s, t, d in sorted(g.edges(data=True), key=lambda e: (e[0], e[1])):
        if d.get("label") == L.DEPLOYED_ON:
            out.setdefault(_name(g, s), []).append(_name(g, t))
    return out


def _svg_timeline(frames: Sequence[Frame], graphs: Sequence[str], platforms: Sequence[str]) -> str:
    cell, left, row = 96.0, 190.0, 22.0
    colour = {p: PLATFORM_PALETTE[i % len(PLATFORM_PALETTE)] for i, p in enumerate(platforms)}
    rows = ["event", *graphs, "errors"]
    width = left + cell * len(frames) + 10
    height = 30 + row * len(rows) + 6
    out = [
        f'<svg class="timeline" xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {_n(width)} {_n(height)}" width="{_n(width)}" height="{_n(height)}" '
        'font-family="DejaVu Sans, Arial, Helvetica, sans-serif" role="img" aria-label="timeline">'
    ]
    for r, name in enumerate(rows):
        y = 30 + row * r
        text = {"event": "step", "errors": "errors (raised ▲ / standing)"}.get(name, name)
        out.append(f'<text x="{left - 8}" y="{_n(y + 15)}" font-size="11" text-anchor="end" fill="#333">{_e(text)}</text>')
    for i, f in enumerate(frames):
        x = left + cell * i
        deployed = _deployed(f.graph)
        out.append(f'<g class="tl-col" data-goto="{i}" data-key="{_e(f.key)}"><title>{_e(f.title)}</title>')
        out.append(f'<rect class="tl-bg" x="{_n(x)}" y="0" width="{_n(cell)}" height="{_n(height)}" fill="transparent"/>')
        when = f.key if f.time is None else f"{f.key} · {seconds_text(f.time)}s"
        out.append(f'<text x="{_n(x + cell / 2)}" y="18" font-size="11" font-weight="700" text-anchor="middle" fill="#222">{_e(when)}</text>')
        ev = f.event if len(f.event) <= 17 else f.event[:16] + "…"
        out.append(f'<text x="{_n(x + cell / 2)}" y="{_n(30 + 15)}" font-size="9.5" text-anchor="middle" fill="#333">{_e(ev)}</text>')
        for r, graph in enumerate(graphs, start=1):
            y = 30 + row * r
            on = deployed.get(graph, [])
            part = (cell - 4) / max(len(on), 1)
            for k, p in enumerate(on):  # side by side when one graph runs on several platforms
                px = x + 2 + part * k
                out.append(
                    f'<rect x="{_n(px)}" y="{_n(y + 3)}" width="{_n(part - (1 if len(on) > 1 else 0))}" height="{_n(row - 6)}" rx="3" '
                    f'fill="{colour.get(p, "#777")}"/>'
                    f'<text x="{_n(px + part / 2)}" y="{_n(y + 15)}" font-size="10" text-anchor="middle" fill="white">{_e(p)}</text>'
                )
        y = 30 + row * (len(rows) - 1)
        if f.standing:
            out.append(f'<rect x="{_n(x + 2)}" y="{_n(y + 5)}" width="{_n(cell - 4)}" height="{_n(row - 10)}" rx="3" fill="#f4a582"/>')
        marks = "▲" * min(len(f.raised), 4) + (" ⚠" if f.violations else "")
        if marks:
            out.append(f'<text x="{_n(x + cell / 2)}" y="{_n(y + 16)}" font-size="12" text-anchor="middle" fill="#b2182b">{_e(marks)}</text>')
        out.append("</g>")
    out.append("</svg>")
    return "".join(out)


# --------------------------------------------------------------------------- side panels
def _list(items: Iterable[str], empty: str, cls: str = "") -> str:
    items = list(items)
    if not items:
        return f'<p class="none">{_e(empty)}</p>'
    return f'<ul class="{cls}">' + "".join(f"<li>{_e(i)}</li>" for i in items) + "</ul>"


def _reasons_table(frame: Frame, platforms: Sequence[str]) -> str:
    deployed = _deployed(frame.graph)
    head = "".join(f"<th>{_e(p)}</th>" for p in platforms)
    rows = []
    for r in frame.reasons:
        cells = []
        failures = dict(r.failures)
        for p in platforms:
            here = " running" if p in deployed.get(r.graph, ()) else ""
            if p in r.acceptable:
                rank = r.acceptable.index(p)
                extra = f" (choice {rank + 1})" if len(r.acceptable) > 1 else ""
                score = f"<div class=\"score\">score {r.scores[rank]:.3g}</div>" if r.scores else ""
                badge = '<div class="badge">● running here</div>' if here else ""
                cells.append(f'<td class="ok{here}" data-platform="{_e(p)}" data-verdict="acceptable">✓ acceptable{_e(extra)}{score}{badge}</td>')
            elif p in failures:
                lines = "".join(f"<li>{_e(line.removeprefix(p + ': '))}</li>" for line in failures[p])
                badge = '<div class="badge">● running here</div>' if here else ""
                cells.append(f'<td class="bad{here}" data-platform="{_e(p)}" data-verdict="rejected">✗ rejected<ul>{lines}</ul>{badge}</td>')
            else:
                why = f"not considered: fixed to {r.fixed}" if r.fixed and r.fixed != p else "not considered"
                cells.append(f'<td class="na" data-platform="{_e(p)}" data-verdict="absent">— {_e(why)}</td>')
        fixed = f'<div class="fixed">fixed: only {_e(r.fixed)}</div>' if r.fixed else ""
        rows.append(f'<tr data-graph="{_e(r.graph)}"><th scope="row">{_e(r.graph)}{fixed}</th>{"".join(cells)}</tr>')
    raw = "".join(
        f"<pre data-graph=\"{_e(r.graph)}\">$ desmon explain … {_e(r.graph)}\n"
        + (f"fixed deployment: only its EXECUTABLE_ON platform {_e(r.fixed)} is considered\n" if r.fixed else "")
        + f"{_e(r.text)}</pre>"
        for r in frame.reasons
    )
    return (
        f'<table class="reasons"><thead><tr><th>graph \\ platform</th>{head}</tr></thead><tbody>{"".join(rows)}</tbody></table>'
        f"<details><summary>as <code>desmon explain</code> prints it</summary>{raw}</details>"
    )


def _panel(frame: Frame) -> str:
    raised = "".join(
        f"<li><b>{_e(headline)}</b>" + (f"<pre>{_e(detail)}</pre>" if detail else "") + "</li>" for headline, detail in frame.raised
    )
    violations = "".join(f'<li class="violation"><b>{_e(name)} VIOLATED</b>: {_e(msg)}</li>' for name, msg in frame.violations)
    parts = [
        f'<h3>Event</h3><p class="event">{_e(frame.event)}</p>',
        "<h3>What the deployer did</h3>" + _list(frame.commands, "nothing (no command)", "commands"),
        "<h3>Errors raised</h3>" + (f'<ul class="raised">{raised}</ul>' if raised else '<p class="none">none</p>'),
        "<h3>Errors standing</h3>" + _list((text for _g, text in frame.standing), "none", "standing"),
        "<h3>Invariants</h3>" + (f'<ul class="violations">{violations}</ul>' if violations else '<p class="none ok">all hold</p>'),
    ]
    if frame.notes:
        parts.append("<h3>Notes</h3>" + _list(frame.notes, "", "notes"))
    return "".join(parts)


# --------------------------------------------------------------------------- the page
CSS = """
*{box-sizing:border-box}
body{margin:0;font:14px/1.4 "DejaVu Sans",Arial,Helvetica,sans-serif;color:#1a1a1a;background:#fafafa}
header{padding:14px 22px 6px;background:#fff;border-bottom:1px solid #ddd}
header h1{margin:0 0 4px;font-size:20px}
header p{margin:2px 0;color:#444}
.banner{margin:8px 0 2px;padding:6px 10px;border-radius:4px;background:#fde0dd;border:1px solid #d73027}
nav{display:flex;gap:6px;align-items:center;padding:10px 22px;background:#fff;border-bottom:1px solid #ddd;position:sticky;top:0;z-index:2}
nav button{font:inherit;padding:4px 12px;border:1px solid #888;border-radius:4px;background:#f4f4f4;cursor:pointer}
nav button:disabled{opacity:.4;cursor:default}
#counter{margin-left:10px;font-weight:600}
.tlwrap{overflow-x:auto;padding:6px 22px;background:#fff;border-bottom:1px solid #ddd}
.tl-col{cursor:pointer}
.tl-col.current .tl-bg{fill:#fff3bf}
.tl-col:hover .tl-bg{fill:#f1f3f5}
main{padding:10px 22px}
.step{display:grid;grid-template-columns:minmax(0,1fr) minmax(260px,330px);gap:14px;align-items:start}
.step[hidden]{display:none}
.step h2{grid-column:1/-1;margin:4px 0;font-size:17px}
.graphbox{overflow-x:auto;background:#fff;border:1px solid #ddd;border-radius:6px;padding:4px}
.side{background:#fff;border:1px solid #ddd;border-radius:6px;padding:4px 12px 10px}
.side h3{font-size:13px;margin:10px 0 3px;color:#555;text-transform:uppercase;letter-spacing:.04em}
.side ul{margin:2px 0;padding-left:18px}
.side pre,.why pre{white-space:pre-wrap;font-size:11.5px;background:#f6f6f6;padding:4px 6px;margin:3px 0;border-radius:3px}
.none{color:#777;margin:2px 0}.ok{color:#1b7837}
.violation{color:#b2182b}
.why{grid-column:1/-1;background:#fff;border:1px solid #ddd;border-radius:6px;padding:4px 12px 10px}
.why h3{font-size:13px;margin:8px 0 6px;color:#555;text-transform:uppercase;letter-spacing:.04em}
table.reasons{border-collapse:collapse;width:100%;font-size:12.5px}
table.reasons th,table.reasons td{border:1px solid #ddd;padding:4px 6px;vertical-align:top;text-align:left}
table.reasons thead th{background:#f1f1f1}
table.reasons td.ok{background:#e5f5e0}
table.reasons td.bad{background:#fde0dd}
table.reasons td.running{outline:2px solid #1b7837;outline-offset:-2px}
table.reasons td ul{margin:2px 0;padding-left:16px}
.badge{color:#1b7837;font-weight:600}.score{color:#555}.fixed{font-weight:400;color:#762a83;font-size:11.5px}
.legend{display:flex;flex-wrap:wrap;gap:12px;font-size:12px;color:#444;margin:6px 0 0}
.legend span{display:inline-flex;align-items:center;gap:4px}
.legend i{display:inline-block;width:22px;height:0;border-top:3px solid}
footer{padding:10px 22px 24px;color:#666;font-size:12px}
"""

JS = """
(function () {
  "use strict";
  var steps = Array.prototype.slice.call(document.querySelectorAll("section.step"));
  var cols = Array.prototype.slice.call(document.querySelectorAll(".tl-col"));
  var counter = document.getElementById("counter");
  var buttons = {first: document.getElementById("first"), prev: document.getElementById("prev"),
                 next: document.getElementById("next"), last: document.getElementById("last"),
                 play: document.getElementById("play")};
  var current = 0, timer = null;
  function show(i) {
    current = Math.max(0, Math.min(steps.length - 1, i));
    steps.forEach(function (s, j) { s.hidden = j !== current; });
    cols.forEach(function (c, j) { c.classList.toggle("current", j === current); });
    counter.textContent = "step " + (current + 1) + " / " + steps.length + ": " + steps[current].getAttribute("data-title");
    buttons.first.disabled = buttons.prev.disabled = current === 0;
    buttons.next.disabled = buttons.last.disabled = current === steps.length - 1;
    document.body.setAttribute("data-current", String(current));
  }
  function stop() { if (timer !== null) { clearInterval(timer); timer = null; buttons.play.textContent = "▶ play"; } }
  buttons.first.addEventListener("click", function () { stop(); show(0); });
  buttons.prev.addEventListener("click", function () { stop(); show(current - 1); });
  buttons.next.addEventListener("click", function () { stop(); show(current + 1); });
  buttons.last.addEventListener("click", function () { stop(); show(steps.length - 1); });
  buttons.play.addEventListener("click", function () {
    if (timer !== null) { stop(); return; }
    if (current === steps.length - 1) { show(0); }
    buttons.play.textContent = "❚❚ pause";
    timer = setInterval(function () { if (current >= steps.length - 1) { stop(); } else { show(current + 1); } }, 1600);
  });
  cols.forEach(function (c) { c.addEventListener("click", function () { stop(); show(Number(c.getAttribute("data-goto"))); }); });
  document.addEventListener("keydown", function (ev) {
    var k = {ArrowLeft: current - 1, ArrowRight: current + 1, Home: 0, End: steps.length - 1}[ev.key];
    if (k !== undefined) { stop(); show(k); ev.preventDefault(); }
  });
  var wanted = (location.hash || "").slice(1), start = 0;
  try { wanted = decodeURIComponent(wanted); } catch (e) { /* a fragment that is no URI escape (a percent sign alone): the first step */ }
  steps.forEach(function (s, j) { if (s.getAttribute("data-key") === wanted || s.id === wanted) { start = j; } });
  show(start);
}());
"""


def _legend() -> str:
    items = [
        (L.DEPLOYED_ON, "solid"), (L.DEPLOYMENT_HISTORY, "dashed"), (L.EXECUTABLE_ON, "solid"),
        (L.HAS_DEVICE, "solid"), (L.RESOLVES, "solid"), (L.IN_CONTEXT, "solid"),
    ]
    out = [f'<span><i style="border-top-color:{EDGE_COLOR[k]};border-top-style:{style}"></i>{_e(k)}</span>' for k, style in items]
    out.append('<span><i style="border-top-color:#ffe066;border-top-width:7px"></i>new at this step</span>')
    out.append('<span><i style="border-top-color:#d73027;border-top-style:dotted"></i>removed at this step</span>')
    out.append('<span><i style="border-top-color:#f08c00"></i>node changed</span>')
    out.append('<span><i style="border-top-color:#d73027"></i>error standing</span>')
    return '<div class="legend">' + "".join(out) + "</div>"


def render_page(title: str, lines: Sequence[str], frames: Sequence[Frame], *, banner: str = "", command: str = "") -> str:
    """The explorer page of ``frames`` (at least one), as one HTML text.

    ``lines`` are shown under the title; ``banner`` (if any) in red; ``command`` is the
    command line that wrote the page, shown in the footer.
    """
    if not frames:
        raise ValueError("the explorer needs at least one frame")
    boxes, heads, width, height = layout(frames)
    full = _union(frames)
    platforms = [_name(full, n) for n in _ordered(full, L.PLATFORM)]
    graphs = [r.graph for r in frames[0].reasons]
    out = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        '<link rel="icon" href="data:,">',
        f"<title>{_e(title)}</title>",
        f"<style>{CSS}</style></head>",
        '<body data-current="0">',
        f"<header><h1>{_e(title)}</h1>" + "".join(f"<p>{_e(line)}</p>" for line in lines),
        f'<div class="banner">{_e(banner)}</div>' if banner else "",
        "</header>",
        '<nav><button id="first" title="first step (Home)">« first</button><button id="prev" title="previous step (←)">◀ prev</button>'
        '<button id="next" title="next step (→)">next ▶</button><button id="last" title="last step (End)">last »</button>'
        '<button id="play" title="step through every 1.6 s">▶ play</button><span id="counter"></span></nav>',
        f'<div class="tlwrap">{_svg_timeline(frames, graphs, platforms)}</div>',
        "<main>",
    ]
    prev = None
    for i, f in enumerate(frames):
        out.append(
            f'<section class="step" id="step-{i}" data-step="{i}" data-key="{_e(f.key)}" data-title="{_e(f.title)}">'
            f"<h2>{_e(f.title)}</h2>"
            f'<div class="graphbox">{_svg_frame(f, prev, boxes, heads, width, height)}{_legend()}</div>'
            f'<div class="side">{_panel(f)}</div>'
            f'<div class="why"><h3>Why: the reasons <code>desmon explain</code> gives at this step</h3>{_reasons_table(f, platforms)}</div>'
            "</section>"
        )
        prev = f
    out.append("</main>")
    footer = "Written by desmon explore; works offline (no server, nothing fetched). Keys: ← → Home End."
    if command:
        footer += f" Command: {command}"
    out.append(f"<footer>{_e(footer)}</footer>")
    out.append(f"<script>{JS}</script></body></html>")
    return "\n".join(part for part in out if part) + "\n"

