"""Timeline plot of a ``desmon run`` trace (JSON Lines, schema in :mod:`desmon.sim.trace`).

Panels, top to bottom, on one time axis:

* **context** -- the robot's action segments, one colour per action of the model (the
  ``run`` record lists them); a dark red strip along the top marks the time in risky
  actions (an object in the hand); unmonitored exposure is shaded red across every panel;
* **one lane per platform** -- the detectors running there (solid once warmed up, hatched
  while warming up, grey while they have no valid input, white with crosses when their
  inputs have no signal model: they run but can never alarm), platform crashes in black;
* **events** -- device / platform faults (labelled above), errors (labelled below),
  injected slips (triangles) and alarms (ticks, coloured by detector). Labels are packed
  into rows so that none overlaps another; those that find no room are counted at the
  row's right end;
* **one panel per resource** the platforms declare (memory, GPU memory, ...) -- per
  platform, background load plus what running detectors consume, against the capacity
  (dashed).

Reads only the trace, so any run (or a trace from another machine) can be drawn.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable

from desmon.errors import ScenarioError
from desmon.model.checks import exact
from desmon.paths import TRACE_FILE, check_input_file, replacing
from desmon.viz.common import plain_text, require_matplotlib

__all__ = ["read_trace", "check_window", "Timeline", "build_timeline", "plot_timeline", "timeline_figure", "action_colors"]

#: the built-in actions' colours (light, so labels and exposure stay readable on them)
ACTION_COLORS = {
    "idle": "#f0f0f0",
    "hold": "#d9d9d9",
    "grasp": "#fdae6b",
    "move_base": "#9ecae1",
    "release": "#a1d99b",
    "rotate_ccw": "#dadaeb",
    "rotate_cw": "#bcbddc",
}
#: colours of the actions a model declares, in declaration order (light, distinct from the built-ins')
EXTRA_ACTION_COLORS = [
    "#fbb4ae", "#ccebc5", "#fed9a6", "#ffffcc", "#e5d8bd", "#fddaec", "#b3e2cd", "#fdcdac", "#cbd5e8", "#f4cae4",
    "#e6f5c9", "#fff2ae", "#f1e2cc", "#8dd3c7", "#ffffb3", "#bebada", "#fb8072", "#80b1d3", "#b3de69", "#fccde5",
]
#: the built-in actions with an object in the hand (the model's own are named in the run record)
_BUILTIN_RISKY = frozenset({"grasp", "hold", "move_base", "release", "rotate_ccw", "rotate_cw"})
#: the colour of the strip that marks the time spent in risky actions
RISKY_EDGE = "#8b0000"
#: heights (in lanes) of an action's bar and of the risky strip above it
ACTION_HEIGHT, RISKY_HEIGHT = 0.58, 0.12
DETECTOR_COLORS = [
    "#1b9e77", "#d95f02", "#7570b3", "#e7298a", "#66a61e", "#e6ab02", "#a6761d", "#1f78b4", "#b15928", "#6a3d9a",
    "#33a02c", "#e31a1c",
]


_HOW = TRACE_FILE[1]


def read_trace(path: str | Path) -> list[dict[str, Any]]:
    """The records of a JSON Lines trace; a ScenarioError names a missing file or bad line."""
    p = check_input_file(path, *TRACE_FILE)
    out: list[dict[str, Any]] = []
    lines: list[int] = []  # the line of each record
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
            if record.get("type") == "run" and out:
                raise ScenarioError(
                    f"{path}:{n}: a second 'run' record (the first is on line {lines[0]}): a trace holds one run; "
                    f"are two traces joined? plot each on its own"
                )
            out.append(record)
            lines.append(n)
    if not out:
        raise ScenarioError(f"{path}: is empty; {_HOW}")
    if out[0].get("type") != "run":
        if "robot" in out[0]:  # (every record of a fleet's trace names its robot)
            raise ScenarioError(
                f"{path}: a fleet's trace (its records name their robots): desmon plot draws one robot's run; write one with: "
                "desmon run SCENARIO --trace run.jsonl on a single-robot scenario"
            )
        raise ScenarioError(f"{path}: does not start with a 'run' record; is it a desmon run trace? {_HOW}")
    _check_platforms(path, out, lines)
    _check_times(path, out, lines)
    _check_records(path, out, lines)
    return out


#: every type of record a run writes (desmon.sim.trace's schema)
RECORD_TYPES = frozenset({
    "run", "load", "consumption", "slip", "action", "exposure", "fact", "reaction", "decision", "error", "ready",
    "no_signal", "invalid", "platform", "fault", "lease", "change", "alarm", "violation", "end",
})


def _check_records(path: str | Path, records: list[dict[str, Any]], lines: list[int]) -> None:
    """Every record is of a type a run writes, none follows the ``end`` record, and a
    detector is stopped, ready or invalid only where a start put it (a record removed by
    hand had left a stop drawn below the platform's own load, without a word)."""
    running: set[tuple[Any, Any]] = set()
    ended = False
    for record, n in zip(records, lines):
        kind = record.get("type")
        if kind not in RECORD_TYPES or ended:
            what = f"a record of type {kind!r}, which a run never writes" if not ended else f"a {kind!r} record after the 'end' record"
            raise ScenarioError(f"{path}:{n}: {what}; is the trace edited or from another program? {_HOW}")
        ended = kind == "end"
        pair = (record.get("graph"), record.get("platform"))
        if kind == "decision" and record.get("ok"):
            if record.get("command") == "start":
                running.add(pair)
            elif pair in running:
                running.discard(pair)
            else:
                _unstarted(path, n, record)
        elif kind in ("ready", "invalid", "no_signal") and pair not in running:
            _unstarted(path, n, record)


def _unstarted(path: str | Path, n: int, record: dict[str, Any]) -> None:
    what = record.get("command", record.get("type"))
    raise ScenarioError(
        f"{path}:{n}: a {what!r} of {record.get('graph')!r} on {record.get('platform')!r}, which no earlier record started; "
        f"is the trace edited? {_HOW}"
    )


def _check_platforms(path: str | Path, records: list[dict[str, Any]], lines: list[int]) -> None:
    """Every platform a record names is one the run record declares: a timeline draws one
    lane per declared platform, so a record on another one would be drawn without a word
    of what is wrong (a hand-edited trace, or records of another run pasted in)."""
    declared = records[0].get("platforms")
    if not isinstance(declared, dict):
        return  # a missing or malformed field is the run record's own check
    for record, n in zip(records[1:], lines[1:]):
        p = record.get("platform")
        if isinstance(p, str) and p not in declared:
            raise ScenarioError(
                f"{path}:{n}: a {record.get('type')!r} record on platform {p!r}, which the run record does not declare "
                f"(it declares {', '.join(map(str, declared)) or 'none'}); is the trace from another run or edited? {_HOW}"
            )


#: the records a run writes ahead of or behind their time (desmon.sim.trace): ground-truth
#: slips all at the start, alarms when the detector consumes the samples
_OUT_OF_ORDER = frozenset({"slip", "alarm"})


def _check_times(path: str | Path, records: list[dict[str, Any]], lines: list[int]) -> None:
    """Every record's time lies within the run's ``[0, horizon]``, and the records a run
    writes as they happen come in time order (a record outside the run would be dropped
    from the drawing, and shuffled ones drawn as nonsense, without a word)."""
    horizon = records[0].get("horizon")
    if not (_finite(horizon) and horizon > 0):
        return  # the run record's own check
    last, last_line = 0.0, lines[0]
    for record, n in zip(records, lines):
        t = record.get("t")
        if not _finite(t):
            continue  # build_timeline names it
        if not -1e-6 <= t <= horizon + 1e-6:  # (times are rounded to the microsecond)
            raise ScenarioError(
                f"{path}:{n}: a {record.get('type')!r} record at t={t:g} s, outside the run's [0, {horizon:g}] s; "
                f"is the trace edited or from another run? {_HOW}"
            )
        if record.get("type") in _OUT_OF_ORDER:
            continue
        if t < last - 1e-6:
            raise ScenarioError(
                f"{path}:{n}: a {record.get('type')!r} record at t={t:g} s after one at t={last:g} s (line {last_line}): "
                f"a run writes its records in time order (slips and alarms aside); is the trace edited? {_HOW}"
            )
        last, last_line = t, n


def check_whole(path: str | Path, records: list[dict[str, Any]]) -> None:
    """The trace holds its run's ``end`` record: ``desmon run`` writes the file only once
    the run is complete, so a trace without one was cut short or edited, and a drawing of
    it would show a run that stopped early as if it had not. (Asked after
    :func:`build_timeline`, whose checks name a bad record first.)"""
    if not any(r.get("type") == "end" for r in records):
        last = records[-1].get("t")
        at = f" after {len(records):,} records (the last at t={last:g} s)" if _finite(last) else ""
        raise ScenarioError(f"{path}: no 'end' record{at}: the trace is cut short, and desmon run writes one whole; {_HOW}")


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
    if start is None and end is not None and end <= 0:
        raise ScenarioError(f"{flags[1]} {end:g}: an empty window (the run starts at 0 s); give {flags[1]} above 0")
    if horizon is not None:
        if start is not None and start >= horizon:
            raise ScenarioError(
                f"{flags[0]} {exact(start)}: at or after the end of the run ({exact(horizon)} s), nothing to draw; "
                f"give {flags[0]} below {exact(horizon)}"
            )
        if end is not None and end > horizon:
            raise ScenarioError(
                f"{flags[1]} {exact(end)}: past the end of the run ({exact(horizon)} s); give {flags[1]} at most {exact(horizon)}, or leave it out"
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
    #: action -> whether it is risky (an object in the hand), in the model's order
    risky: dict[str, bool] = field(default_factory=dict)
    #: resource -> platform -> [(t, in use)] (``usage["memory"]`` is ``memory``)
    usage: dict[str, dict[str, list[tuple[float, float]]]] = field(default_factory=dict)
    #: resource -> platform -> capacity (``capacities["memory"]`` is ``capacity``)
    capacities: dict[str, dict[str, float]] = field(default_factory=dict)
    #: graphs whose inputs have no signal model (the run's ``no_signal_model``): they never warm up
    no_signal: list[str] = field(default_factory=list)


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


def _amounts(entry: Any, name: str) -> dict[str, float]:
    """Every ``resource: amount`` of a run record entry (memory first, 0 when missing)."""
    if not isinstance(entry, dict):
        raise ValueError(f"run record: the entry of {name} is {entry!r}, not an object of resource amounts")
    out = {"memory": _mb(entry, name)}
    for r, v in entry.items():
        if r != "memory" and v is not None:
            out[str(r)] = _non_negative(v, f"run record: {r} of {name}")
    return out


def _build(records: list[dict[str, Any]], horizon: float, start: float | None, end: float | None) -> Timeline:
    head = records[0]
    t0 = 0.0 if start is None else float(start)
    t1 = horizon if end is None else float(end)
    tl = Timeline(str(head.get("scenario", "?")), str(head.get("deployer", "?")), t0, t1)
    end = next((r for r in reversed(records) if r.get("type") == "end"), None)
    reader = _Reader(tl, head, end)
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

    def __init__(self, tl: Timeline, head: dict[str, Any], end: dict[str, Any] | None = None) -> None:
        self.tl = tl
        platforms = head.get("platforms") or {}
        self.platforms: list[str] = list(platforms.keys())
        tl.capacity = {p: _mb(v, p) for p, v in platforms.items() if v.get("memory") is not None}
        tl.capacities = {"memory": tl.capacity}
        for p, v in platforms.items():
            for r, cap in _amounts(v, p).items():
                if r != "memory":
                    tl.capacities.setdefault(r, {})[p] = cap
        tl.usage = {r: {} for r in tl.capacities}
        tl.memory = tl.usage["memory"]
        #: graph -> {resource: amount} a running instance consumes
        self.consumption = {g: _amounts(v, g) for g, v in (head.get("graphs") or {}).items()}
        tl.graphs = list(self.consumption)  # declaration order: the same detector keeps its colour across plots
        actions = head.get("actions")
        if isinstance(actions, dict):
            tl.risky = {str(a): bool(v.get("risky")) if isinstance(v, dict) else True for a, v in actions.items()}
        missing = (end or {}).get("no_signal_model") or {}
        tl.no_signal = [str(g) for g in missing] if isinstance(missing, dict) else []
        self.running: dict[tuple[str, str], tuple[float, str]] = {}  # (graph, platform) -> (since, phase)
        self.uses: dict[tuple[str, str], dict[str, float]] = {}  # (graph, platform) -> what that instance consumes
        self.load: dict[tuple[str, str], float] = {}  # (platform, resource) -> background load
        self.used: dict[tuple[str, str], float] = {}  # (platform, resource) -> consumed by running instances
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
            "consumption": self._consumption,
            "no_signal": self._no_signal,
        }

    def read(self, r: dict[str, Any]) -> None:
        t = float(r.get("t", 0.0))
        kind = r.get("type")
        handler = self.handlers.get(kind) if isinstance(kind, str) else None  # other types are skipped
        if handler is not None:
            handler(r, t)

    # -- helpers ---------------------------------------------------------------------
    def _point(self, p: str, r: str, t: float) -> None:
        """What ``p`` has in use of resource ``r`` from ``t`` on."""
        key = (p, r)
        self.tl.usage.setdefault(r, {}).setdefault(p, []).append((t, self.load.get(key, 0.0) + self.used.get(key, 0.0)))

    def _consume(self, p: str, use: dict[str, float], sign: float, t: float) -> None:
        for r, amount in use.items():
            self.used[(p, r)] = self.used.get((p, r), 0.0) + sign * amount
            self._point(p, r, t)

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
        name = str(r.get("action"))
        self.tl.actions.append((t, t + _amount(r, "duration"), name))
        if name not in self.tl.risky:  # a trace without the run record's actions
            self.tl.risky[name] = name in _BUILTIN_RISKY or name not in ACTION_COLORS

    def _decision(self, r: dict[str, Any], t: float) -> None:
        if not r.get("ok"):
            return
        g, p = str(r["graph"]), str(r["platform"])
        self._seen(p)
        if g not in self.tl.graphs:
            self.tl.graphs.append(g)
        if r.get("command") == "start":
            self._phase_change(g, p, t, "warming")
            self.uses[(g, p)] = use = dict(self.consumption.get(g, {"memory": 0.0}))
            self._consume(p, use, 1.0, t)
        elif r.get("command") == "stop":
            self._phase_change(g, p, t, None)
            self._consume(p, self.uses.pop((g, p), self.consumption.get(g, {"memory": 0.0})), -1.0, t)

    def _consumption(self, r: dict[str, Any], t: float) -> None:
        """A requirement change: running instances of the graph consume the new amounts."""
        g = str(r["graph"])
        new = _amounts(r.get("resources") or {}, g)
        self.consumption[g] = new
        for (graph, p), old in list(self.uses.items()):
            if graph == g:
                delta = {res: new.get(res, 0.0) - old.get(res, 0.0) for res in set(new) | set(old)}
                self._consume(p, {res: d for res, d in sorted(delta.items()) if d}, 1.0, t)
                self.uses[(graph, p)] = dict(new)

    def _ready(self, r: dict[str, Any], t: float) -> None:
        if (r.get("graph"), r.get("platform")) in self.running:
            self._phase_change(str(r["graph"]), str(r["platform"]), t, "valid")

    def _no_signal(self, r: dict[str, Any], t: float) -> None:
        if (r.get("graph"), r.get("platform")) in self.running:
            self._phase_change(str(r["graph"]), str(r["platform"]), t, "no_signal")

    def _invalid(self, r: dict[str, Any], t: float) -> None:
        if (r.get("graph"), r.get("platform")) in self.running:
            self._phase_change(str(r["graph"]), str(r["platform"]), t, "invalid")

    def _load(self, r: dict[str, Any], t: float) -> None:
        p = str(r["platform"])
        resource = str(r.get("resource") or "memory")
        self._seen(p)
        self.load[(p, resource)] = _amount(r, "amount")
        self._point(p, resource, t)

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
        """End every interval still open at ``horizon``; order the platform lanes; a
        detector with no signal model never warms up: its warming phase is drawn as such."""
        tl, platforms = self.tl, self.platforms
        for (g, p), (since, phase) in self.running.items():
            tl.runs.setdefault(p, []).append((since, horizon, g, phase))
        for p, since in self.down_since.items():
            tl.down.setdefault(p, []).append((since, horizon))
        if self.exposure_since is not None:
            tl.exposure.append((self.exposure_since, horizon))
        tl.runs = {p: tl.runs.get(p, []) for p in platforms + [q for q in tl.runs if q not in platforms]}
        silent = set(tl.no_signal)
        if silent:
            tl.runs = {
                p: [(a, b, g, "no_signal" if g in silent and ph == "warming" else ph) for a, b, g, ph in v] for p, v in tl.runs.items()
            }
        for series in tl.usage.values():
            for p, pts in series.items():
                pts.append((horizon, pts[-1][1]))


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
    tl.usage = {r: {p: _clip_steps(v, t0, t1) for p, v in series.items()} for r, series in tl.usage.items()}
    tl.memory = tl.usage.setdefault("memory", {})


def _clip_steps(points: list[tuple[float, float]], t0: float, t1: float) -> list[tuple[float, float]]:
    """A step series cut to ``[t0, t1]``: the value in force at ``t0``, the changes inside, the end."""
    if not points or (t0 <= points[0][0] and points[-1][0] <= t1):
        return points
    before = [v for t, v in points if t <= t0]
    out = [(t0, before[-1])] if before else []
    out += [(t, v) for t, v in points if t0 < t < t1]
    if out:
        out.append((t1, out[-1][1]))
    return out


# -- drawing ----------------------------------------------------------------------------------
DPI = 110
WIDTH_IN = 13.0
#: the axes span this fraction of the figure's width (the right margin holds the resource legends)
LEFT, RIGHT = 0.085, 0.845
LANE_IN = 0.55  # one context or platform lane
ROW_IN = 0.2  # one row of the events panel (a row of labels, or of markers)
RESOURCE_IN = 1.7  # one resource panel
GAP_IN = 0.12  # between the panels
LABEL_PT = 7  # event labels
MAX_LABEL_ROWS = 4  # rows of fault labels (above their markers) and of error labels (below theirs)


@dataclass
class _Label:
    """An event label placed in a row: its text, left end (in seconds), row and colour."""

    text: str
    x: float
    row: int
    color: str


@dataclass
class _Rows:
    """Labels packed into rows (none overlaps another), and how many found no room."""

    labels: list[_Label] = field(default_factory=list)
    left_out: int = 0

    @property
    def rows(self) -> int:
        return 1 + max((lb.row for lb in self.labels), default=-1)


def _pack(items: list[tuple[float, str, str]], tl: Timeline, width_px: float, measure: Any) -> _Rows:
    """Greedy row packing of ``(t, text, colour)`` labels, each centred on its ``t`` where
    the axes allow: a label goes to the lowest row whose last label ends (with a gap)
    before it starts; with every row taken it is left out (and counted)."""
    span = tl.end - tl.start
    px_per_s = width_px / span if span > 0 else 0.0
    ends = [-math.inf] * MAX_LABEL_ROWS
    out = _Rows()
    gap = 6.0
    for t, text, color in sorted(items, key=lambda x: x[0]):
        w = measure(text)
        if w > width_px:  # wider than the whole panel: no row can hold it
            out.left_out += 1
            continue
        left = (t - tl.start) * px_per_s - w / 2
        left = max(0.0, min(left, width_px - w))
        for row in range(MAX_LABEL_ROWS):
            if left >= ends[row] + gap:
                ends[row] = left + w
                out.labels.append(_Label(text, tl.start + left / px_per_s if px_per_s else tl.start, row, color))
                break
        else:
            out.left_out += 1
    return out


def _resources(tl: Timeline) -> list[str]:
    """The resource panels: memory first, then every other resource declared or used, by name."""
    names = [r for r in tl.usage if tl.usage[r] or tl.capacities.get(r)]
    return sorted(names, key=lambda r: (r != "memory", r))


def action_colors(tl: Timeline) -> dict[str, str]:
    """One colour per action: a built-in keeps its own, the model's own actions take
    :data:`EXTRA_ACTION_COLORS` in the order the run record lists them (then as they appear)."""
    out: dict[str, str] = {}
    extra = 0
    for name in [*tl.risky, *(n for _a, _b, n in tl.actions)]:
        if name in out:
            continue
        if name in ACTION_COLORS:
            out[name] = ACTION_COLORS[name]
        else:
            out[name] = EXTRA_ACTION_COLORS[extra % len(EXTRA_ACTION_COLORS)]
            extra += 1
    return out


def timeline_figure(tl: Timeline) -> Any:
    """The matplotlib figure of ``tl`` (the caller saves and closes it); its texts as written."""
    require_matplotlib()
    with plain_text():
        return _timeline_figure(tl)


def _timeline_figure(tl: Timeline) -> Any:
    plt = require_matplotlib()
    from matplotlib.font_manager import FontProperties

    fig = plt.figure(figsize=(WIDTH_IN, 4.0), dpi=DPI)
    renderer = fig.canvas.get_renderer()
    font = FontProperties(size=LABEL_PT)

    def measure(text: str) -> float:
        return renderer.get_text_width_height_descent(text, font, ismath=False)[0]

    width_px = (RIGHT - LEFT) * WIDTH_IN * DPI
    faults = _pack([(t, text, "black") for t, text in tl.faults], tl, width_px, measure)
    errors = _pack([(t, f"{kind}: {g}", "#b2182b") for t, kind, g in tl.errors], tl, width_px, measure)
    platforms = list(tl.runs)
    lanes = ["context", *platforms]
    resources = _resources(tl)
    # the events panel, bottom up: slips and alarms, error labels, errors, faults, fault labels
    ev_rows = 1.6 + errors.rows + 1 + 1 + faults.rows + 0.4
    heights = [LANE_IN * len(lanes) + 0.3, ROW_IN * ev_rows] + [RESOURCE_IN] * len(resources)
    total = sum(heights) + GAP_IN * (len(heights) - 1) + (0.45 if resources else 0.35)
    fig.set_size_inches(WIDTH_IN, total)
    axes = []
    top = total
    for i, h in enumerate(heights):
        top -= h + (GAP_IN if i else 0.0)
        ax = fig.add_axes((LEFT, top / total, RIGHT - LEFT, h / total), sharex=axes[0] if axes else None)
        axes.append(ax)
    ax, axe, res_axes = axes[0], axes[1], axes[2:]
    color_of = {g: DETECTOR_COLORS[i % len(DETECTOR_COLORS)] for i, g in enumerate(tl.graphs)}
    for a, b in tl.exposure:
        for each in axes:
            each.axvspan(a, b, color="#e41a1c", alpha=0.13, lw=0)
    y = {name: len(lanes) - 1 - i for i, name in enumerate(lanes)}
    colors = action_colors(tl)
    _draw_lanes(ax, tl, y, color_of, colors, measure)
    ax.set_yticks([y[n] for n in lanes], lanes)
    ax.set_ylim(-0.6, len(lanes) - 0.4)
    ax.set_xlim(tl.start, tl.end)
    ys = _draw_events(axe, tl, color_of, faults, errors)
    axe.set_ylim(0, ev_rows)
    axe.set_yticks(list(ys.values()), list(ys.keys()))
    for each in axes:
        each.grid(axis="x", color="#eeeeee")
        each.set_axisbelow(True)
        if each is not axes[-1]:
            each.tick_params(axis="x", labelbottom=False)
    for r, axr in zip(resources, res_axes):
        _draw_resource(axr, tl, r)
    axes[-1].set_xlabel("simulated time (s)")
    ax.legend(
        handles=_legend(plt, tl, color_of, colors), fontsize=7, ncol=6, loc="lower left", bbox_to_anchor=(0.0, 1.02),
        frameon=False, title=f"{tl.scenario} — deployer {tl.deployer}", title_fontsize=11, alignment="left",
    )
    return fig


def plot_timeline(tl: Timeline, path: str | Path) -> Path:
    """Draw ``tl`` to a PNG file."""
    plt = require_matplotlib()
    fig = timeline_figure(tl)
    out = Path(path)
    try:
        with replacing(out, "wb") as fh:  # exactly this file, whatever its name; a failed write leaves the one there was
            fig.savefig(fh, dpi=DPI, bbox_inches="tight", format="png")
    finally:
        plt.close(fig)
    return out


def _draw_lanes(ax: Any, tl: Timeline, y: dict[str, int], color_of: dict[str, str], colors: dict[str, str], measure: Any) -> None:
    """The context lane (action segments, named where the name fits) and one lane per
    platform (crashes, detectors by phase)."""
    span = tl.end - tl.start
    px_per_s = (RIGHT - LEFT) * WIDTH_IN * DPI / span if span > 0 else 0.0
    yc = y["context"]
    for a, b, name in tl.actions:
        wide = (b - a) * px_per_s > 4  # an outline only where it leaves the colour visible
        ax.barh(yc - 0.06, b - a, left=a, height=ACTION_HEIGHT, color=colors[name], edgecolor="#777777", lw=0.4 if wide else 0.0)
        if measure(name) * 8 / LABEL_PT + 8 < (b - a) * px_per_s:  # drawn at 8 pt: only where it fits its segment
            ax.text((a + b) / 2, yc - 0.06, name, ha="center", va="center", fontsize=8)
    # risky actions (an object in the hand): a dark red strip along the top of the lane
    for a, b in _merged((a, b) for a, b, name in tl.actions if tl.risky.get(name, True)):
        ax.barh(yc + 0.31, b - a, left=a, height=RISKY_HEIGHT, color=RISKY_EDGE, lw=0)
    for p, runs in tl.runs.items():
        for a, b in tl.down.get(p, []):
            ax.barh(y[p], b - a, left=a, height=0.85, color="black", alpha=0.75)
        for a, b, g, phase in runs:
            color = color_of.get(g, "#999999")
            if phase == "warming":
                ax.barh(y[p], b - a, left=a, height=0.6, color="white", edgecolor=color, hatch="////", lw=0.8)
            elif phase == "no_signal":
                ax.barh(y[p], b - a, left=a, height=0.6, color="white", edgecolor=color, hatch="xx", lw=1.2, ls="--")
            elif phase == "invalid":
                ax.barh(y[p], b - a, left=a, height=0.6, color="#bbbbbb", edgecolor=color, lw=0.8)
            else:
                ax.barh(y[p], b - a, left=a, height=0.6, color=color, edgecolor=color, lw=0.5)


def _merged(intervals: Iterable[tuple[float, float]]) -> list[tuple[float, float]]:
    """Touching or overlapping intervals joined (in time order)."""
    out: list[tuple[float, float]] = []
    for a, b in sorted(intervals):
        if out and a <= out[-1][1] + 1e-9:
            out[-1] = (out[-1][0], max(out[-1][1], b))
        else:
            out.append((a, b))
    return out


def _draw_events(ax: Any, tl: Timeline, color_of: dict[str, str], faults: _Rows, errors: _Rows) -> dict[str, float]:
    """The events panel: slips and alarms at the bottom, errors with their labels in rows
    below them, faults with their labels in rows above them. Returns the rows' y by name."""
    slips_y = 0.8
    error_y = 1.6 + errors.rows + 0.5
    fault_y = error_y + 1.0
    for t, _kind in tl.slips:
        ax.plot([t], [slips_y], marker="^", color="#e41a1c", ms=8, markeredgecolor="black", mew=0.5)
    for t, g in tl.alarms:
        ax.plot([t, t], [slips_y - 0.45, slips_y + 0.45], color=color_of.get(g, "#444444"), lw=1.0)
    for t, text in tl.faults:
        repaired = text.endswith((" repaired", " up", " joins"))
        ax.plot([t], [fault_y], marker="^" if repaired else "v", color="#2b8cbe" if repaired else "black", ms=7)
    for t, _kind, _g in tl.errors:
        ax.plot([t], [error_y], marker="X", color="#b2182b", ms=9, markeredgecolor="white", mew=0.5)
    for lb in faults.labels:
        ax.text(lb.x, fault_y + 1.0 + lb.row, lb.text, fontsize=LABEL_PT, ha="left", va="center", color=lb.color)
    for lb in errors.labels:
        ax.text(lb.x, error_y - 1.0 - lb.row, lb.text, fontsize=LABEL_PT, ha="left", va="center", color=lb.color)
    for rows, y, what in ((faults, fault_y, "fault"), (errors, error_y, "error")):
        if rows.left_out:
            ax.text(
                1.005, y, f"+{rows.left_out} {what} label{'s' if rows.left_out != 1 else ''} not shown",
                transform=ax.get_yaxis_transform(), fontsize=LABEL_PT, ha="left", va="center", color="#555555",
            )
    return {"slips, alarms": slips_y, "errors": error_y, "faults": fault_y}


def _draw_resource(axr: Any, tl: Timeline, resource: str) -> None:
    """Per platform, what is in use of ``resource`` (steps) against its capacity (dashed)."""
    series = tl.usage.get(resource, {})
    caps = tl.capacities.get(resource, {})
    every = [*tl.runs, *sorted(p for r in tl.usage.values() for p in r if p not in tl.runs)]
    order = list(dict.fromkeys(every))  # a platform keeps its colour in every resource panel
    names = [p for p in order if p in series or p in caps]
    for p in names:
        color = f"C{order.index(p) % 10}"
        pts = series.get(p)
        if pts:
            axr.step([a for a, _v in pts], [v for _a, v in pts], where="post", label=f"{p} used", lw=1.4, color=color)
        if p in caps and math.isfinite(caps[p]):
            axr.axhline(caps[p], color=color, ls="--", lw=0.9, label=f"{p} capacity")
    axr.set_ylabel("memory (MB)" if resource == "memory" else resource)
    axr.set_ylim(bottom=0)
    axr.grid(color="#eeeeee")
    if names:
        entries = len(axr.get_legend_handles_labels()[1])
        fits = max(1, int(RESOURCE_IN * DPI / 15.5))  # entries of 7 pt one column holds beside the panel
        axr.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.005, 1.0), frameon=False, ncol=-(-entries // fits))


def _legend(plt: Any, tl: Timeline, color_of: dict[str, str], colors: dict[str, str]) -> list[Any]:
    """Legend handles: the actions shown (risky ones bordered), the detectors shown (in
    declaration order), then the symbols the picture uses."""
    from matplotlib.patches import Patch

    shown_actions = list(dict.fromkeys(n for _a, _b, n in tl.actions))
    order = sorted(shown_actions, key=list(colors).index)
    handles: list[Any] = [
        Patch(facecolor=colors[n], edgecolor="#777777", lw=0.4, label=n + (" (risky)" if tl.risky.get(n, True) else "")) for n in order
    ]
    if any(tl.risky.get(n, True) for n in shown_actions):
        handles.append(Patch(facecolor=RISKY_EDGE, label="in a risky action (object in hand)"))
    phases = {ph for runs in tl.runs.values() for _a, _b, _g, ph in runs}
    shown = {g for runs in tl.runs.values() for _a, _b, g, _ph in runs} | {g for _t, g in tl.alarms}
    silent = set(tl.no_signal)
    handles += [
        Patch(facecolor=color_of[g], label=g + (" (no signal model)" if g in silent else "")) for g in tl.graphs if g in shown
    ]
    symbols = [
        ("warming" in phases, Patch(facecolor="white", edgecolor="#555555", hatch="////", label="warming up")),
        ("no_signal" in phases, Patch(facecolor="white", edgecolor="#555555", hatch="xx", ls="--", label="no signal model: cannot alarm")),
        ("invalid" in phases, Patch(facecolor="#bbbbbb", label="no valid input")),
        (any(tl.down.values()), Patch(facecolor="black", alpha=0.75, label="platform down")),
        (bool(tl.exposure), Patch(facecolor="#e41a1c", alpha=0.2, label="unmonitored exposure")),
        (bool(tl.slips), plt.Line2D([], [], marker="^", color="#e41a1c", ls="", label="slip injected")),
        (bool(tl.alarms), plt.Line2D([], [], color="#444444", label="alarm")),
        (bool(tl.errors), plt.Line2D([], [], marker="X", color="#b2182b", ls="", label="error")),
        (bool(tl.faults), plt.Line2D([], [], marker="v", color="black", ls="", label="fault")),
        (any(t.endswith((" repaired", " up", " joins")) for _x, t in tl.faults),
         plt.Line2D([], [], marker="^", color="#2b8cbe", ls="", label="repair / back up")),
    ]
    return handles + [h for present, h in symbols if present]
