"""Timeline plot of a ``desmon run`` trace (JSON Lines, schema in :mod:`desmon.sim.trace`).

Lanes, top to bottom, on one time axis:

* **context** — the robot's action segments; unmonitored exposure shaded red across all lanes;
* **one lane per platform** — the detectors running there (solid once warmed up, hatched
  while warming up, grey while they have no valid input), platform crashes in black;
* **events** — device / platform faults, injected slips (triangles), alarms (ticks,
  coloured by detector) and errors (red crosses);
* **memory** — per platform, background load plus what running detectors consume,
  against the capacity (dashed).

Reads only the trace, so any run (or a trace from another machine) can be drawn.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable

from desmon.errors import ScenarioError
from desmon.paths import TRACE_FILE, check_input_file
from desmon.viz.common import require_matplotlib

__all__ = ["read_trace", "check_window", "Timeline", "build_timeline", "plot_timeline"]

ACTION_COLORS = {
    "idle": "#f0f0f0",
    "hold": "#d9d9d9",
    "grasp": "#fdae6b",
    "move_base": "#9ecae1",
    "release": "#a1d99b",
    "rotate_ccw": "#dadaeb",
    "rotate_cw": "#bcbddc",
}
DETECTOR_COLORS = ["#1b9e77", "#d95f02", "#7570b3", "#e7298a", "#66a61e", "#e6ab02"]


_HOW = TRACE_FILE[1]


def read_trace(path: str | Path) -> list[dict[str, Any]]:
    """The records of a JSON Lines trace; a ScenarioError names a missing file or bad line."""
    p = check_input_file(path, *TRACE_FILE)
    out: list[dict[str, Any]] = []
    with p.open("rb") as fh:
        head = fh.read(2)
        if head == b"\x1f\x8b":
            raise ScenarioError(f"{path}: gzip-compressed; decompress it first (gunzip -c {path} > run.jsonl)")
        fh.seek(0)
        n = 0
        for n, raw in enumerate(fh, start=1):
            try:
                line = raw.decode("utf-8")
            except UnicodeDecodeError:
                raise ScenarioError(f"{path}:{n}: not UTF-8 text (a binary file?); desmon plot reads a JSON Lines trace: {_HOW}") from None
            if not line.strip():
                continue
            try:
                record = json.loads(line)
            except json.JSONDecodeError as exc:
                cut = " (the last line, cut off: is the file truncated?)" if not raw.endswith(b"\n") else ""
                raise ScenarioError(f"{path}:{n}: not a JSON Lines trace record ({exc.msg}){cut}; {_HOW}") from None
            except (ValueError, RecursionError) as exc:  # a number of over 4300 digits, nesting too deep
                raise ScenarioError(f"{path}:{n}: not a JSON Lines trace record ({str(exc).split(';')[0]}); {_HOW}") from None
            if not isinstance(record, dict):
                shape = "a JSON array" if isinstance(record, list) else f"a JSON {type(record).__name__}"
                raise ScenarioError(
                    f"{path}:{n}: {shape}, not a record; a trace holds one JSON object per line (JSON Lines): {_HOW}"
                )
            out.append(record)
    if not out:
        raise ScenarioError(f"{path}: is empty; {_HOW}")
    if out[0].get("type") != "run":
        raise ScenarioError(f"{path}: does not start with a 'run' record; is it a desmon run trace? {_HOW}")
    return out


def check_window(
    start: float | None, end: float | None, horizon: float | None = None, *, flags: tuple[str, str] = ("--from", "--to")
) -> None:
    """The rule for a timeline window ``[start, end]`` (either may be open) within ``[0, horizon]``.

    ``flags`` name the bounds in the ScenarioError, as the user wrote them.
    """
    for flag, v in zip(flags, (start, end)):
        if v is not None and not (_finite(v) and v >= 0):
            raise ScenarioError(f"{flag} {v:g}: give a time in seconds, 0 or more" if _is_number(v) else f"{flag} {v!r}: give a time in seconds")
    if start is not None and end is not None and start >= end:
        raise ScenarioError(f"{flags[0]} {start:g} {flags[1]} {end:g}: an empty window; give {flags[1]} after {flags[0]}")
    if horizon is not None:
        if start is not None and start >= horizon:
            raise ScenarioError(
                f"{flags[0]} {start:g}: at or after the end of the run ({horizon:g} s), nothing to draw; give {flags[0]} below {horizon:g}"
            )
        if end is not None and end > horizon:
            raise ScenarioError(
                f"{flags[1]} {end:g}: past the end of the run ({horizon:g} s); give {flags[1]} at most {horizon:g}, or leave it out"
            )


@dataclass
class Timeline:
    """A trace digested into intervals and points, clipped to ``[start, end]``."""

    scenario: str
    deployer: str
    start: float
    end: float
    actions: list[tuple[float, float, str]] = field(default_factory=list)
    exposure: list[tuple[float, float]] = field(default_factory=list)
    # platform -> [(t0, t1, graph, phase)] with phase "warming" | "valid" | "invalid"
    runs: dict[str, list[tuple[float, float, str, str]]] = field(default_factory=dict)
    down: dict[str, list[tuple[float, float]]] = field(default_factory=dict)
    faults: list[tuple[float, str]] = field(default_factory=list)
    slips: list[tuple[float, str]] = field(default_factory=list)
    alarms: list[tuple[float, str]] = field(default_factory=list)
    errors: list[tuple[float, str, str]] = field(default_factory=list)
    memory: dict[str, list[tuple[float, float]]] = field(default_factory=dict)
    capacity: dict[str, float] = field(default_factory=dict)
    graphs: list[str] = field(default_factory=list)


def _clip(intervals: Iterable[tuple[float, float]], start: float, end: float) -> list[tuple[float, float]]:
    return [(max(a, start), min(b, end)) for a, b in intervals if b > start and a < end]


def _is_number(v: Any) -> bool:
    return not isinstance(v, bool) and isinstance(v, (int, float))


def _finite(v: Any) -> bool:
    return _is_number(v) and math.isfinite(v)


def build_timeline(
    records: list[dict[str, Any]],
    start: float | None = None,
    end: float | None = None,
    *,
    flags: tuple[str, str] = ("--from", "--to"),
) -> Timeline:
    """Digest trace records into a :class:`Timeline` (pure; no plotting).

    A record whose fields have the wrong type is a ScenarioError naming the record; so is
    a window outside the run (``flags`` name its bounds, see :func:`check_window`).
    """
    if not records:
        raise ScenarioError(f"the trace holds no records; {_HOW}")
    for n, r in enumerate(records, start=1):
        if not isinstance(r, dict) or not _finite(r.get("t", 0.0)):
            raise ScenarioError(f"trace record {n} ({str(r)[:80]}): needs a finite numeric 't'; is this a desmon run trace?")
    head = records[0]
    horizon = head.get("horizon")
    if horizon is None:
        horizon = max(r.get("t", 0.0) for r in records)
    if not _finite(horizon) or horizon <= 0:
        raise ScenarioError(f"trace 'run' record: horizon {horizon!r} is not a positive number of seconds; nothing to draw")
    check_window(start, end, float(horizon), flags=flags)
    try:
        return _build(records, float(horizon), start, end)
    except ScenarioError:
        raise  # already names its record (a ScenarioError is a ValueError too): not wrapped again
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise ScenarioError(f"trace 'run' record does not follow the desmon run schema ({type(exc).__name__}: {exc}); {_HOW}") from None


def _non_negative(v: Any, where: str) -> float:
    """``v`` as a finite number >= 0; a ValueError says ``where`` it was read."""
    if not _finite(v) or v < 0:
        raise ValueError(f"{where} {v!r} is not a finite number >= 0")
    return float(v)


def _amount(r: dict[str, Any], key: str) -> float:
    return _non_negative(r.get(key, 0.0), key)


def _mb(entry: dict[str, Any], name: str) -> float:
    return _non_negative(entry.get("memory", 0), f"run record: memory of {name}")


def _build(records: list[dict[str, Any]], horizon: float, start: float | None, end: float | None) -> Timeline:
    head = records[0]
    t0 = 0.0 if start is None else float(start)
    t1 = horizon if end is None else float(end)
    tl = Timeline(str(head.get("scenario", "?")), str(head.get("deployer", "?")), t0, t1)
    reader = _Reader(tl, head)
    for n, r in enumerate(records[1:], start=2):
        try:
            reader.read(r)
        except KeyError as exc:
            raise ScenarioError(f"trace record {n} ({str(r)[:80]}): no field {exc}; {_HOW}") from None
        except (TypeError, ValueError, AttributeError) as exc:
            raise ScenarioError(f"trace record {n} ({str(r)[:80]}): {exc}; {_HOW}") from None
    reader.close(horizon)
    _clip_window(tl, t0, t1)
    return tl


class _Reader:
    """Digests trace records one by one into ``tl`` (intervals still open are kept here
    until :meth:`close`); one method per record type."""

    def __init__(self, tl: Timeline, head: dict[str, Any]) -> None:
        self.tl = tl
        self.platforms: list[str] = list((head.get("platforms") or {}).keys())
        tl.capacity = {p: _mb(v, p) for p, v in (head.get("platforms") or {}).items() if v.get("memory") is not None}
        self.consumption = {g: _mb(v, g) for g, v in (head.get("graphs") or {}).items()}
        tl.graphs = list(self.consumption)  # declaration order: the same detector keeps its colour across plots
        self.running: dict[tuple[str, str], tuple[float, str]] = {}  # (graph, platform) -> (since, phase)
        self.load: dict[str, float] = {}
        self.used: dict[str, float] = {}
        self.down_since: dict[str, float] = {}
        self.exposure_since: float | None = None
        self.handlers = {
            "action": self._action,
            "decision": self._decision,
            "ready": self._ready,
            "invalid": self._invalid,
            "load": self._load,
            "platform": self._platform,
            "fault": self._fault,
            "slip": self._slip,
            "alarm": self._alarm,
            "error": self._error,
            "exposure": self._exposure,
        }

    def read(self, r: dict[str, Any]) -> None:
        t = float(r.get("t", 0.0))
        kind = r.get("type")
        handler = self.handlers.get(kind) if isinstance(kind, str) else None  # other types are skipped
        if handler is not None:
            handler(r, t)

    # -- helpers ---------------------------------------------------------------------
    def _mem_point(self, p: str, t: float) -> None:
        self.tl.memory.setdefault(p, []).append((t, self.load.get(p, 0.0) + self.used.get(p, 0.0)))

    def _phase_change(self, g: str, p: str, t: float, phase: str | None) -> None:
        key = (g, p)
        if key in self.running:
            since, old = self.running.pop(key)
            self.tl.runs.setdefault(p, []).append((since, t, g, old))
        if phase is not None:
            self.running[key] = (t, phase)

    def _seen(self, p: str | None) -> None:
        if p and p not in self.platforms:
            self.platforms.append(p)

    # -- one method per record type ------------------------------------------------------
    def _action(self, r: dict[str, Any], t: float) -> None:
        self.tl.actions.append((t, t + _amount(r, "duration"), str(r.get("action"))))

    def _decision(self, r: dict[str, Any], t: float) -> None:
        if not r.get("ok"):
            return
        g, p = str(r["graph"]), str(r["platform"])
        self._seen(p)
        if g not in self.tl.graphs:
            self.tl.graphs.append(g)
        if r.get("command") == "start":
            self._phase_change(g, p, t, "warming")
            self.used[p] = self.used.get(p, 0.0) + self.consumption.get(g, 0.0)
        elif r.get("command") == "stop":
            self._phase_change(g, p, t, None)
            self.used[p] = self.used.get(p, 0.0) - self.consumption.get(g, 0.0)
        self._mem_point(p, t)

    def _ready(self, r: dict[str, Any], t: float) -> None:
        if (r.get("graph"), r.get("platform")) in self.running:
            self._phase_change(str(r["graph"]), str(r["platform"]), t, "valid")

    def _invalid(self, r: dict[str, Any], t: float) -> None:
        if (r.get("graph"), r.get("platform")) in self.running:
            self._phase_change(str(r["graph"]), str(r["platform"]), t, "invalid")

    def _load(self, r: dict[str, Any], t: float) -> None:
        p = str(r["platform"])
        self._seen(p)
        self.load[p] = _amount(r, "amount")
        self._mem_point(p, t)

    def _platform(self, r: dict[str, Any], t: float) -> None:
        p = str(r["platform"])
        if not r.get("up"):
            self.down_since[p] = t
        elif p in self.down_since:
            self.tl.down.setdefault(p, []).append((self.down_since.pop(p), t))

    def _fault(self, r: dict[str, Any], t: float) -> None:
        self.tl.faults.append((t, str(r.get("event", ""))))

    def _slip(self, r: dict[str, Any], t: float) -> None:
        self.tl.slips.append((t, f"{r.get('kind', '')} {r.get('direction', '')}".strip()))

    def _alarm(self, r: dict[str, Any], t: float) -> None:
        self.tl.alarms.append((t, str(r.get("detector"))))

    def _error(self, r: dict[str, Any], t: float) -> None:
        self.tl.errors.append((t, str(r.get("kind")), str(r.get("graph"))))

    def _exposure(self, r: dict[str, Any], t: float) -> None:
        if r.get("state") == "start":
            self.exposure_since = t
        elif self.exposure_since is not None:
            self.tl.exposure.append((self.exposure_since, t))
            self.exposure_since = None

    def close(self, horizon: float) -> None:
        """End every interval still open at ``horizon``; order the platform lanes."""
        tl, platforms = self.tl, self.platforms
        for (g, p), (since, phase) in self.running.items():
            tl.runs.setdefault(p, []).append((since, horizon, g, phase))
        for p, since in self.down_since.items():
            tl.down.setdefault(p, []).append((since, horizon))
        if self.exposure_since is not None:
            tl.exposure.append((self.exposure_since, horizon))
        tl.runs = {p: tl.runs.get(p, []) for p in platforms + [q for q in tl.runs if q not in platforms]}
        for p in platforms:
            if p in tl.memory:
                tl.memory[p].append((horizon, tl.memory[p][-1][1]))


def _clip_window(tl: Timeline, t0: float, t1: float) -> None:
    """Keep what falls in ``[t0, t1]``, intervals cut at its ends."""
    tl.actions = [(max(a, t0), min(b, t1), n) for a, b, n in tl.actions if b > t0 and a < t1]
    tl.exposure = _clip(tl.exposure, t0, t1)
    tl.runs = {p: [(max(a, t0), min(b, t1), g, ph) for a, b, g, ph in v if b > t0 and a < t1] for p, v in tl.runs.items()}
    tl.down = {p: _clip(v, t0, t1) for p, v in tl.down.items()}
    tl.faults = [x for x in tl.faults if t0 <= x[0] <= t1]
    tl.slips = [x for x in tl.slips if t0 <= x[0] <= t1]
    tl.alarms = [x for x in tl.alarms if t0 <= x[0] <= t1]
    tl.errors = [x for x in tl.errors if t0 <= x[0] <= t1]


def plot_timeline(tl: Timeline, path: str | Path) -> Path:
    """Draw ``tl`` to a PNG file."""
    plt = require_matplotlib()

    platforms = list(tl.runs)
    color_of = {g: DETECTOR_COLORS[i % len(DETECTOR_COLORS)] for i, g in enumerate(tl.graphs)}
    lanes = ["context", *platforms, "events"]
    fig = plt.figure(figsize=(13, 1.0 + 0.55 * len(lanes) + 2.2))
    grid = fig.add_gridspec(2, 1, height_ratios=[0.55 * len(lanes) + 0.4, 2.0], hspace=0.12)
    ax = fig.add_subplot(grid[0])
    axm = fig.add_subplot(grid[1], sharex=ax)
    y = {name: len(lanes) - 1 - i for i, name in enumerate(lanes)}

    for a, b in tl.exposure:
        ax.axvspan(a, b, color="#e41a1c", alpha=0.13, lw=0)
        axm.axvspan(a, b, color="#e41a1c", alpha=0.13, lw=0)
    _draw_lanes(ax, tl, y, color_of)
    _draw_events(ax, tl, y["events"], color_of)
    ax.set_yticks([y[n] for n in lanes], [n if n in ("context", "events") else f"{n}" for n in lanes])
    ax.set_ylim(-0.8, len(lanes) - 0.3)
    ax.set_xlim(tl.start, tl.end)
    ax.tick_params(axis="x", labelbottom=False)
    ax.set_title(f"{tl.scenario} — deployer {tl.deployer}", loc="left", fontsize=11)
    ax.grid(axis="x", color="#eeeeee")
    ax.set_axisbelow(True)
    axm.set_axisbelow(True)
    _draw_memory(axm, tl)
    ax.legend(handles=_legend(plt, tl, color_of), fontsize=7, ncol=6, loc="lower left", bbox_to_anchor=(0.0, 1.06), frameon=False)
    out = Path(path)
    fig.savefig(out, dpi=110, bbox_inches="tight", format="png")  # exactly this file, whatever its name
    plt.close(fig)
    return out


def _draw_lanes(ax: Any, tl: Timeline, y: dict[str, int], color_of: dict[str, str]) -> None:
    """The context lane (action segments) and one lane per platform (crashes, detectors by phase)."""
    for a, b, name in tl.actions:
        ax.barh(y["context"], b - a, left=a, height=0.7, color=ACTION_COLORS.get(name, "#cccccc"), edgecolor="#777777", lw=0.5)
        if b - a > (tl.end - tl.start) * 0.04:
            ax.text((a + b) / 2, y["context"], name, ha="center", va="center", fontsize=8)
    for p, runs in tl.runs.items():
        for a, b in tl.down.get(p, []):
            ax.barh(y[p], b - a, left=a, height=0.85, color="black", alpha=0.75)
        for a, b, g, phase in runs:
            color = color_of.get(g, "#999999")
            if phase == "warming":
                ax.barh(y[p], b - a, left=a, height=0.6, color="white", edgecolor=color, hatch="////", lw=0.8)
            elif phase == "invalid":
                ax.barh(y[p], b - a, left=a, height=0.6, color="#bbbbbb", edgecolor=color, lw=0.8)
            else:
                ax.barh(y[p], b - a, left=a, height=0.6, color=color, edgecolor=color, lw=0.5)


def _draw_events(ax: Any, tl: Timeline, ev: int, color_of: dict[str, str]) -> None:
    """The events lane: faults, injected slips, alarms and errors."""
    for t, text in tl.faults:
        ax.plot([t], [ev + 0.22], marker="v", color="black", ms=7)
        if len(tl.faults) <= 12:
            ax.text(t, ev + 0.42, text, fontsize=7, ha="center", va="bottom")
    for t, _kind in tl.slips:
        ax.plot([t], [ev - 0.05], marker="^", color="#e41a1c", ms=8, markeredgecolor="black", mew=0.5)
    for t, g in tl.alarms:
        ax.plot([t, t], [ev - 0.38, ev - 0.2], color=color_of.get(g, "#444444"), lw=1.0)
    for t, kind, g in tl.errors:
        ax.plot([t], [ev + 0.02], marker="X", color="#b2182b", ms=9, markeredgecolor="white", mew=0.5)
        if len(tl.errors) <= 8:
            ax.text(t, ev - 0.5, f"{kind}: {g}", fontsize=7, ha="left", va="top", color="#b2182b")


def _draw_memory(axm: Any, tl: Timeline) -> None:
    """Per platform, memory used (steps) against its capacity (dashed)."""
    for p, pts in sorted(tl.memory.items()):
        xs = [a for a, _v in pts]
        vs = [v for _a, v in pts]
        line = axm.step(xs, vs, where="post", label=f"{p} used", lw=1.4)[0]
        if p in tl.capacity:
            axm.axhline(tl.capacity[p], color=line.get_color(), ls="--", lw=0.9, label=f"{p} capacity")
    axm.set_ylabel("memory (MB)")
    axm.set_ylim(bottom=0)
    axm.set_xlabel("simulated time (s)")
    axm.grid(color="#eeeeee")
    if tl.memory:
        axm.legend(fontsize=7, ncol=3, loc="upper left", framealpha=0.85)


def _legend(plt: Any, tl: Timeline, color_of: dict[str, str]) -> list[Any]:
    """Legend handles: the detectors shown (in declaration order), then the fixed symbols."""
    from matplotlib.patches import Patch

    shown = {g for runs in tl.runs.values() for _a, _b, g, _ph in runs} | {g for _t, g in tl.alarms}
    handles: list[Any] = [Patch(facecolor=color_of[g], label=g) for g in tl.graphs if g in shown]
    handles += [
        Patch(facecolor="white", edgecolor="#555555", hatch="////", label="warming up"),
        Patch(facecolor="#bbbbbb", label="no valid input"),
        Patch(facecolor="black", alpha=0.75, label="platform down"),
        Patch(facecolor="#e41a1c", alpha=0.2, label="unmonitored exposure"),
        plt.Line2D([], [], marker="^", color="#e41a1c", ls="", label="slip injected"),
        plt.Line2D([], [], color="#444444", label="alarm"),
        plt.Line2D([], [], marker="X", color="#b2182b", ls="", label="error"),
        plt.Line2D([], [], marker="v", color="black", ls="", label="fault"),
    ]
    return handles
