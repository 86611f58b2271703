"""Repository snapshots drawn the way the paper's Fig. 5 shows them.

Columns: requirements | deployment descriptions | platforms | devices. Positions come
from the *complete* graph (every node that ever exists), so the snapshots of t0..t3 can
be laid side by side and compared: only edges change.
"""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

import networkx as nx

from desmon.model.checks import seconds_text
from desmon.paths import replacing
from desmon.viz.common import COLORS, plain_text, require_matplotlib

__all__ = ["layout", "draw_snapshot", "draw_snapshots", "snapshot_figure"]

COLUMNS = ("Requirement", "Deployment", "Platform", "Device")
#: x of each column and the half width of its boxes (data units), so arrows end at box edges.
COLUMN_X = {"Requirement": 0.0, "Deployment": 3.4, "Platform": 7.4, "Device": 10.2}
HALF_WIDTH = {"Requirement": 1.45, "Deployment": 1.1, "Platform": 0.5, "Device": 0.8}
SHOWN_EDGES = ("REQUIRES", "DEPLOYED_ON", "DEPLOYMENT_HISTORY", "EXECUTABLE_ON", "HAS_DEVICE")


def layout(full: nx.MultiDiGraph) -> dict[str, tuple[float, float]]:
    """Stable positions: one column per label, nodes in insertion order top to bottom."""
    pos: dict[str, tuple[float, float]] = {}
    for label in COLUMNS:
        nodes = sorted((d.get("order", 0), n) for n, d in full.nodes(data=True) if d.get("label") == label)
        count = len(nodes)
        for i, (_o, n) in enumerate(nodes):
            pos[n] = (COLUMN_X[label], (count - 1) / 2.0 - i)
    return pos


def _name(g: nx.MultiDiGraph, n: str) -> str:
    d = g.nodes[n]
    label = d.get("label")
    if label == "Requirement":
        return str(d.get("description", n))
    if label == "Platform":
        mem = (d.get("capacities") or {}).get("memory")
        load = (d.get("load") or {}).get("memory")
        text = str(d.get("name", n))
        if mem is not None:
            text += f"\n{mem:g} MB" + (f", load {load:g}" if load else "")
        return text + ("\n(down)" if d.get("up") is False else "")
    if label == "Device" and d.get("working") is False:
        return f"{d.get('name', n)} (failed)"
    return str(d.get("name", n))


def _face(g: nx.MultiDiGraph, n: str) -> tuple[str, str]:
    """(box colour, text colour): failed devices grey, crashed platforms dark."""
    d = g.nodes[n]
    if d.get("label") == "Device" and d.get("working") is False:
        return "#e0e0e0", "#777777"
    if d.get("label") == "Platform" and d.get("up") is False:
        return "#444444", "white"
    return COLORS.get(str(d.get("label")), "white"), "black"


def _draw(ax, g: nx.MultiDiGraph, pos: dict[str, tuple[float, float]], title: str):  # type: ignore[no-untyped-def]
    """Draw snapshot ``g`` into ``ax``; returns the title's Text."""
    head = ax.set_title(title, fontsize=11, loc="left")
    ax.axis("off")
    xs = [p[0] for p in pos.values()]
    ys = [p[1] for p in pos.values()]
    ax.set_xlim(min(xs) - 1.6, max(xs) + 1.0)
    ax.set_ylim(min(ys) - 1.0, max(ys) + 1.0)
    for label in COLUMNS:
        ax.text(COLUMN_X[label], max(ys) + 0.7, label, ha="center", fontsize=9, fontweight="bold", color="#444444")
    for s, t, d in g.edges(data=True):
        label = d.get("label")
        if label not in SHOWN_EDGES or s not in pos or t not in pos:
            continue
        (x1, y1), (x2, y2) = pos[s], pos[t]
        direction = 1.0 if x2 > x1 else -1.0
        x1 += direction * HALF_WIDTH[g.nodes[s]["label"]]
        x2 -= direction * HALF_WIDTH[g.nodes[t]["label"]]
        style = "--" if label == "DEPLOYMENT_HISTORY" else "-"
        width = 2.6 if label == "DEPLOYED_ON" else (1.6 if label in ("DEPLOYMENT_HISTORY", "EXECUTABLE_ON") else 0.9)
        # a fixed deployment's EXECUTABLE_ON edge bows upwards, so a DEPLOYED_ON edge between
        # the same two boxes stays visible beside it
        rad = -0.22 if label == "EXECUTABLE_ON" else 0.0
        ax.annotate(
            "",
            xy=(x2, y2),
            xytext=(x1, y1),
            arrowprops=dict(arrowstyle="-|>", color=COLORS[label], lw=width, linestyle=style,
                            shrinkA=0, shrinkB=2, connectionstyle=f"arc3,rad={rad}"),
        )
        if label in ("DEPLOYED_ON", "DEPLOYMENT_HISTORY", "EXECUTABLE_ON"):
            times = "".join(f" {a}={seconds_text(d[a])}s" for a in ("start", "stop") if isinstance(d.get(a), (int, float)))
            mx, my = (x1 + x2) / 2, (y1 + y2) / 2 + (0.32 if label == "EXECUTABLE_ON" else 0.0)
            ax.text(mx, my, f"{label}{times}", fontsize=7, color=COLORS[label], ha="center", va="center", zorder=3,
                    bbox=dict(boxstyle="round,pad=0.2", fc="white", ec=COLORS[label], lw=0.5))
    for n, (x, y) in pos.items():
        if n not in g:
            continue
        face, ink = _face(g, n)
        ax.text(x, y, _name(g, n), ha="center", va="center", fontsize=7.5, color=ink, zorder=4,
                bbox=dict(boxstyle="round,pad=0.35", fc=face, ec="#555555", lw=0.8))
    return head


def draw_snapshot(g: nx.MultiDiGraph, path: str | Path, *, full: nx.MultiDiGraph | None = None, title: str = "") -> Path:
    """Draw one snapshot to a PNG file; ``full`` fixes the layout (defaults to ``g``)."""
    return draw_snapshots([(title, g)], path, full=full, columns=1)


def draw_snapshots(
    panels: Sequence[tuple[str, nx.MultiDiGraph]],
    path: str | Path,
    *,
    full: nx.MultiDiGraph | None = None,
    columns: int = 2,
) -> Path:
    """Several snapshots side by side in one PNG (e.g. Fig. 5a-d), one shared layout."""
    plt = require_matplotlib()
    fig = snapshot_figure(panels, full=full, columns=columns)
    out = Path(path)
    try:
        with replacing(out, "wb") as fh:  # exactly this file, whatever its name; a failed write leaves the one there was
            fig.savefig(fh, dpi=110, format="png")
    finally:
        plt.close(fig)
    return out


def snapshot_figure(
    panels: Sequence[tuple[str, nx.MultiDiGraph]], *, full: nx.MultiDiGraph | None = None, columns: int = 2
):  # type: ignore[no-untyped-def]
    """The matplotlib figure :func:`draw_snapshots` saves (the caller closes it); its texts as written."""
    require_matplotlib()
    with plain_text():
        return _snapshot_figure(panels, full=full, columns=columns)


def _snapshot_figure(panels: Sequence[tuple[str, nx.MultiDiGraph]], *, full: nx.MultiDiGraph | None, columns: int):  # type: ignore[no-untyped-def]
    plt = require_matplotlib()
    full = full if full is not None else panels[-1][1]
    pos = layout(full)
    rows = (len(panels) + columns - 1) // columns
    # each row as tall as its longest title needs, so no title is cut or runs into a panel
    lines = [max(t.count("\n") + 1 for t, _g in panels[r * columns:(r + 1) * columns]) for r in range(rows)]
    heights = [4.4 + 0.2 * n for n in lines]
    fig, axes = plt.subplots(
        rows, columns, figsize=(8.5 * columns, sum(heights)), squeeze=False, gridspec_kw={"height_ratios": heights}
    )
    for ax in axes.flat:
        ax.axis("off")
    titles = [_draw(ax, g, pos, title) for ax, (title, g) in zip(axes.flat, panels)]
    fig.tight_layout()
    # a title line wider than its panel (long names, capitals) is set smaller, never cut
    renderer = fig.canvas.get_renderer()
    column = fig.bbox.width / columns
    for _round in range(2):  # the layout moves a little once a title shrinks
        for i, t in enumerate(titles):
            box = t.get_window_extent(renderer)
            room = (i % columns + 1) * column - 8 - box.x0
            if box.width > room:
                t.set_fontsize(t.get_fontsize() * room / box.width * 0.98)
        fig.tight_layout()
    return fig
