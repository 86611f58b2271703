"""Presenting checker results: text report, numbered traces, JSON (ITF-like), a pytest."""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from desmon.errors import CheckerError, ModelError
from desmon.paths import GENERATED_TEST_HEAD
from desmon.model.codec import constraint_from_json, constraint_to_json, event_from_json, event_to_json, json_object
from desmon.model.events import Event
from desmon.deployment.guard import CRASH
from desmon.verify.search import NOT_CHECKED, CheckResult
from desmon.verify.trace import Counterexample, Label, Step, rule_of, where_in_reaction
from desmon.verify.state import Key

__all__ = [
    "format_result", "unmodelled_lines", "format_stats", "stats_to_json", "format_trace", "result_to_json", "counterexample_pytest", "event_to_json", "event_from_json",
    "constraint_to_json", "constraint_from_json", "labels_from_json", "initial_fails_from_json", "key_to_json",
    "SavedCounterexample", "read_counterexample", "format_replay_head", "format_divergence", "format_replay_verdict",
]


def format_trace(steps: tuple[Step, ...] | list[Step], *, indent: str = "  ") -> str:
    """Numbered steps ``event -> what changed``."""
    lines = []
    for s in steps:
        changes = "; ".join(s.changes)
        lines.append(f"{indent}{s.index:>2}. {s.title()} -> {changes}")
    return "\n".join(lines)


def format_counterexample(c: Counterexample) -> str:
    if c.invariant == CRASH:  # the deployer's fault (desmon.deployment.guard): the path to the reaction that failed
        where = f"right after `{c.during}`" if c.during else "before its first command"
        head = f"CRASHED in the reaction of step {c.length} (the shortest path to it), {where}"
        return f"{head}:\n{format_trace(c.steps)}\n  => the deployer {c.message}"
    head = f"VIOLATED {c.invariant} after {c.length} step{'s' if c.length != 1 else ''} (shortest)"
    if c.during:
        head += f", {where_in_reaction(c.during)}"
    return f"{head}:\n{format_trace(c.steps)}\n  => {c.invariant}: {c.message}"


def _covered(r: CheckResult) -> str:
    """How many states the orbits of a symmetry-reduced search cover, as the states line says it."""
    return f" (orbits covering {r.states_covered:,} states)" if r.symmetry and r.states_covered is not None else ""


#: what a scenario whose bounds enable no event lacks (verify's and fuzz's warning)
NOTHING_ENABLED_FIX = (
    "list what the environment may change (actions, devices, platforms, loads, joins, requirement_changes) "
    "in the scenario's checker=Bounds(...)"
)


def format_result(r: CheckResult) -> str:
    blind = "".join(f" (not {n}: {NOT_CHECKED.get(n, 'not checked here')})" for n in r.not_checked)
    lines = [f"{r.scenario} -- deployer {r.deployer} -- invariants: {', '.join(r.invariants)}{blind}" + (" -- symmetry reduction" if r.symmetry else "")]
    for c in r.counterexamples:
        lines.append("")
        lines.append(format_counterexample(c))
    lines.append("")
    verdict = r.verdict + (f" ({r.reason})" if r.reason else "")
    lines.append(f"verdict: {verdict}")
    lines.append(
        f"states: {r.states:,}{_covered(r)}  transitions: {r.transitions:,}  depth: {r.depth}  time: {r.seconds:.2f}s  "
        f"{r.states_per_second:,.0f} states/s  {r.transitions_per_second:,.0f} transitions/s  peak memory: {r.peak_mb:.0f} MB"
        + (f" (+ {r.workers} workers, each at most {r.peak_workers_mb:.0f} MB)" if r.worker_levels else "")
    )
    if r.engine == "table":
        lines.append(f"engine: table ({r.records:,} recorded runs of the core and the invariants, replayed for the rest)")
    else:
        lines.append("engine: direct" + (f" ({r.engine_note})" if r.engine_note else ""))
    lines += _event_lines(r)
    if r.rules:
        lines.append("selector contexts exercised: " + ", ".join(f"{c or '(none)'} {n:,}" for c, n in sorted(r.rules.items(), key=lambda x: str(x[0]))))
    if r.branches:
        lines.append("deployer branches: " + ", ".join(f"{b} {n:,}" for b, n in sorted(r.branches.items())))
    lines += unmodelled_lines(r.unmodelled)
    return "\n".join(lines) + "\n"


def unmodelled_lines(unmodelled: tuple[str, ...], what: str = "what this verdict leaves out") -> list[str]:
    """The block under a verdict (or a fuzz's pass: ``what``) naming what its model leaves
    out of the scenario's World (:func:`desmon.verify.bounds.unmodelled`); none if nothing."""
    if not unmodelled:
        return []
    return [f"{what} of the World (docs/design.md §6):", *(f"  - {line}" for line in unmodelled)]


def _event_lines(r: CheckResult) -> list[str]:
    """The events the search enabled, with a warning where some never changed the state,
    or where none was ever enabled (HOLDS then covers the initial state alone)."""
    kinds = sorted(set(r.enabled) | set(r.new_states))
    if not kinds:
        if r.verdict == "HOLDS" and not r.incomplete:
            return [f"warning: no event was ever enabled, so HOLDS covers the initial state alone: {NOTHING_ENABLED_FIX}"]
        return []
    lines = ["events (enabled / new states): " + ", ".join(f"{k} {r.enabled[k]:,}/{r.new_states[k]:,}" for k in kinds)]
    dead = [k for k in kinds if not r.changed[k]]
    if dead and r.verdict == "HOLDS":
        lines.append("  warning: dead event kinds (never changed the state; a scenario bug?): " + ", ".join(dead))
    return lines


# -- JSON ------------------------------------------------------------------------------------
# The codec of model values (events, requirements) is desmon.model.codec; re-exported here.


def labels_from_json(counterexample: object, *, where: str = "counterexample") -> tuple[Label, ...]:
    """The ``(event, failing start indices)`` of each step of a counterexample written by
    ``desmon verify --json`` (one of its ``counterexamples``), after the initial state: what
    :meth:`RepositoryRun.step <desmon.verify.replay.RepositoryRun.step>` replays."""
    c = json_object(where, counterexample, '{"states": [...]}')
    states = c.get("states")
    if not isinstance(states, list) or not states:
        raise CheckerError(f"{where}.states = {states!r} is not a non-empty list of states: re-run desmon verify --json")
    first = json_object(f"{where}.states[0]", states[0], '{"event": null, ...}')
    if first.get("event") is not None:
        raise CheckerError(f"{where}.states[0].event = {first.get('event')!r}: the initial state has no event (null); re-run desmon verify --json")
    out: list[Label] = []
    for i, state in enumerate(states[1:], start=1):
        at = f"{where}.states[{i}]"
        s = json_object(at, state, '{"event": {...}, "fail_indices": []}')
        event = event_from_json(s.get("event"), where=f"{at}.event")
        out.append((event, _fails_from_json(at, s)))
    return tuple(out)


def initial_fails_from_json(counterexample: object, *, where: str = "counterexample") -> tuple[int, ...]:
    """The starts of the first reaction that failed by the checker's choice, as a
    counterexample written by ``desmon verify --json`` gives them (its ``states[0]``;
    :func:`labels_from_json` has checked its shape): what :class:`RepositoryRun
    <desmon.verify.replay.RepositoryRun>` takes as ``initial_fails``."""
    first = json_object(f"{where}.states[0]", json_object(where, counterexample, '{"states": [...]}')["states"][0], '{"event": null, ...}')
    return _fails_from_json(f"{where}.states[0]", first)


def _fails_from_json(at: str, s: dict[str, Any]) -> tuple[int, ...]:
    """A saved state's ``fail_indices``, checked against its ``failed_starts``."""
    fails = s.get("fail_indices")
    if fails is None and not s.get("failed_starts"):
        fails = []  # written before fail_indices, with no failing start: nothing is lost
    if fails is None:
        raise CheckerError(f"{at} lists failed starts but no fail_indices (written by an older desmon): re-run desmon verify --json")
    if not isinstance(fails, list) or any(isinstance(x, bool) or not isinstance(x, int) or x < 0 for x in fails):
        raise CheckerError(f"{at}.fail_indices = {fails!r} is not a list of non-negative integers (the failing Control.start calls)")
    if fails != sorted(set(fails)):
        raise CheckerError(f"{at}.fail_indices = {fails!r}: give each failing Control.start call once, in increasing order")
    listed = s.get("failed_starts")
    # before refused_starts, failed_starts listed the refused starts too: it may be longer
    older = "refused_starts" not in s
    if isinstance(listed, list) and (len(listed) < len(fails) if older else len(listed) != len(fails)):
        raise CheckerError(
            f"{at}: fail_indices names {len(fails)} failing start(s) but failed_starts lists {len(listed)}: "
            "a hand edit? re-run desmon verify --json"
        )
    return tuple(fails)


def key_to_json(k: Key) -> dict[str, Any]:
    return {
        "context": k.context,
        "failed_devices": list(k.failed),
        "platforms_down": list(k.down),
        "loads": {p: dict(items) for p, items in k.loads},
        "deployments": [list(d) for d in k.deployments],
        "standing_errors": list(k.standing),
        **({"changed_requirements": {g: [r.describe() for r in reqs] for g, reqs in k.specs}} if k.specs else {}),
    }


def counterexample_to_json(c: Counterexample) -> dict[str, Any]:
    return {
        "invariant": c.invariant,
        "message": c.message,
        "during": c.during,
        "length": c.length,
        "states": [
            {
                "step": s.index, "event": event_to_json(s.event), "failed_starts": list(s.failed_starts),
                "fail_indices": list(s.fail_indices),
                "refused_starts": [{"start": start, "rule": rule_of(why), "reason": why} for start, why in s.refused],
                "raised_errors": list(s.raised), "changes": list(s.changes), "state": key_to_json(s.key),
            }
            for s in c.steps
        ],
    }


def result_to_json(r: CheckResult, params: dict[str, str]) -> dict[str, Any]:
    """The result as ``desmon verify --json`` writes it; ``params``: the run's ``-p NAME=VALUE``
    parameters (``desmon verify --replay`` refuses to replay it with other ones)."""
    from desmon.verify.deployers import portable_spec

    return {
        "scenario": r.scenario,
        "deployer": portable_spec(r.deployer),  # a file's path made absolute: --replay from any directory
        "params": dict(params),
        "verdict": r.verdict,
        "reason": r.reason,
        "states": r.states,
        **({"symmetry": True, "states_covered": r.states_covered} if r.symmetry else {}),
        "transitions": r.transitions,
        "depth": r.depth,
        "seconds": round(r.seconds, 3),
        "incomplete": r.incomplete,
        "interrupted": r.interrupted,
        "timeout": r.timeout,
        "max_memory_mb": r.max_memory,
        "peak_mb": round(r.peak_mb, 1),
        "workers": r.workers,
        "worker_levels": r.worker_levels,
        "engine": r.engine,
        "engine_note": r.engine_note,
        "records": r.records,
        "invariants": list(r.invariants),
        "not_checked": {n: NOT_CHECKED.get(n, "") for n in r.not_checked},
        "unmodelled": list(r.unmodelled),
        **_exercised(r),
        "counterexamples": [counterexample_to_json(c) for c in r.counterexamples],
    }


def _exercised(r: CheckResult) -> dict[str, Any]:
    """What the search exercised, as the text report's event, context and branch lines say it:
    per event kind its events enabled over the states expanded and the new states they reached;
    the dead kinds the text warns of; the visits per selector context (``null``: none yet); the
    deployer's branches taken."""
    kinds = sorted(set(r.enabled) | set(r.new_states))
    return {
        "events": {k: {"enabled": r.enabled[k], "new_states": r.new_states[k]} for k in kinds},
        "dead_event_kinds": [k for k in kinds if not r.changed[k]] if r.verdict == "HOLDS" else [],
        "contexts": [[c, n] for c, n in sorted(r.rules.items(), key=lambda x: str(x[0]))],
        "branches": dict(sorted(r.branches.items())),
    }


def stats_to_json(r: CheckResult) -> dict[str, Any]:
    """The search's throughput (``desmon verify --stats --json``, key "stats")."""
    return {
        "states_per_s": round(r.states_per_second, 1) if r.seconds > 0 else None,
        "bytes_per_state": round(r.bytes_per_state, 1),
        "start_mb": round(r.start_mb, 1),
        "peak_mb": round(r.peak_mb, 1),
        "records": r.records if r.engine == "table" else None,
    }


def format_stats(r: CheckResult) -> str:
    """The line ``desmon verify --stats`` prints after the report."""
    rate = f"{r.states_per_second:,.0f} states/s" if r.seconds > 0 else "states/s not measured"
    runs = f", {r.records:,} recorded runs of the core (table engine)" if r.engine == "table" else ""
    return (f"stats: {rate}, {r.bytes_per_state:,.0f} bytes/state "
            f"(peak {r.peak_mb:,.0f} MB resident, {r.start_mb:,.0f} MB when the search began){runs}")


# -- reading a counterexample back (desmon verify --replay) ---------------------------------------
_WRITE_ONE = "write one with: desmon verify SCENARIO --json cex.json"


@dataclass(frozen=True, slots=True)
class SavedCounterexample:
    """One counterexample of a ``desmon verify --json`` file, read back and checked."""

    source: str  # the file
    number: int  # which one (1 = the first)
    count: int  # how many the file holds
    scenario: str  # the scenario's name
    deployer: str  # the deployer's name (its --deployer spec)
    params: tuple[tuple[str, str], ...]  # the -p NAME=VALUE of the run

    def refuse_other_params(self, given: dict[str, str], to: str) -> None:
        """A one-line CheckerError if ``given`` (a command's ``-p``) are not the parameters
        the file was written with; ``to``: what the command does with it ("replay it")."""
        params = tuple(sorted(given.items()))
        if params != self.params:
            def shown(ps: tuple[tuple[str, str], ...]) -> str:
                return " ".join(f"-p {k}={v}" for k, v in ps) or "no -p parameters"

            raise CheckerError(
                f"{self.source} was written with {shown(self.params)}, this command gives {shown(params)}: "
                f"pass the same -p NAME=VALUE to {to}"
            )
    invariants: tuple[str, ...]  # the invariants the run checked
    invariant: str
    message: str
    during: str | None
    labels: tuple[Label, ...]  # the steps after the initial state
    states: tuple[dict[str, Any], ...]  # the recorded key of each state (key_to_json), the initial one first
    initial_fails: tuple[int, ...] = ()  # the starts of the first reaction that failed by the checker's choice


def read_counterexample(path: str | Path, number: int | None = None) -> SavedCounterexample:
    """Counterexample ``number`` (default: the first) of the JSON file ``path`` written by
    ``desmon verify --json``. Whatever is wrong (not JSON, a field of the wrong type or a
    bad value, a number out of range) is a one-line :class:`CheckerError` naming it."""
    from desmon.deployment.invariants import get_invariants

    src = str(path)
    top = json_object(src, _read_json(path), '{"scenario": ..., "deployer": ..., "counterexamples": [...]}')
    scenario, deployer = (_field(src, top, k, str) for k in ("scenario", "deployer"))
    params = _field(src, top, "params", dict)
    if not all(isinstance(v, str) for v in params.values()):
        raise CheckerError(f"{src}: params = {params!r} is not an object of NAME: VALUE texts, e.g. {{\"hand_memory\": \"256\"}}")
    checked = tuple(map(str, _field(src, top, "invariants", list)))
    twice = sorted({n for n in checked if checked.count(n) > 1})
    if twice:
        raise CheckerError(f"{src}: invariants names {', '.join(twice)} twice: list each checked invariant once")
    try:
        get_invariants(checked)
    except ModelError as exc:
        raise CheckerError(f"{src}: invariants: {exc}") from None
    n, c = _pick(src, top, number)
    where = f"{src}: counterexamples[{n - 1}]"
    invariant = _field(where, c, "invariant", str)
    if invariant == CRASH:
        raise CheckerError(
            f"{where} is the path to a reaction in which the deployer crashed, not an invariant's counterexample: "
            "fix the deployer, then re-run desmon verify (it reports the crash again if it still happens)"
        )
    if invariant not in checked:
        raise CheckerError(f"{where}.invariant = {invariant!r} is not one of the invariants the run checked ({', '.join(checked)})")
    during = c.get("during")
    if during is not None and not isinstance(during, str):
        raise CheckerError(f"{where}.during = {during!r} is neither null nor the command text it was violated after")
    labels = labels_from_json(c, where=where)
    _check_numbering(where, c)
    states = tuple(
        _field(f"{where}.states[{i}]", json_object(f"{where}.states[{i}]", s, '{"event": ..., "state": {...}}'), "state", dict)
        for i, s in enumerate(c["states"])
    )
    return SavedCounterexample(
        src, n, len(top["counterexamples"]), scenario, deployer, tuple(sorted(params.items())),
        checked, invariant, _field(where, c, "message", str), during, labels, states, initial_fails_from_json(c, where=where),
    )


def _check_numbering(where: str, c: dict[str, Any]) -> None:
    """The counterexample's ``length`` and its states' ``step`` numbers agree with its list of
    states (a file cut or edited by hand would otherwise replay as a shorter path, "fixed")."""
    states = c.get("states")
    if not isinstance(states, list):
        return  # (labels_from_json names it)
    length = c.get("length")
    if isinstance(length, bool) or length != len(states) - 1:
        raise CheckerError(
            f"{where}.length = {'missing' if 'length' not in c else repr(length)}, but it lists {len(states)} states (the initial one and {len(states) - 1} "
            f"step{'' if len(states) == 2 else 's'}): "
            f"the file was cut or edited; {_WRITE_ONE}"
        )
    for i, state in enumerate(states):
        step = state.get("step", i) if isinstance(state, dict) else i
        if isinstance(step, bool) or step != i:
            raise CheckerError(f"{where}.states[{i}].step = {step!r}, not {i}: the states are out of order or cut; {_WRITE_ONE}")


def _read_json(path: str | Path) -> object:
    try:
        return json.loads(Path(path).read_bytes().decode("utf-8"))
    except UnicodeDecodeError:
        raise CheckerError(f"{path}: not a text file, so not the JSON desmon verify --json writes; {_WRITE_ONE}") from None
    except json.JSONDecodeError as exc:
        raise CheckerError(f"{path}: not JSON ({exc.msg} at line {exc.lineno} column {exc.colno}); {_WRITE_ONE}") from None
    except (ValueError, RecursionError) as exc:  # a number of over 4300 digits, nesting too deep for the parser
        why = " ".join(str(exc).split(";")[0].split())
        raise CheckerError(f"{path}: not JSON that desmon can read ({why}); {_WRITE_ONE}") from None


def _pick(src: str, top: dict[str, Any], number: int | None) -> tuple[int, dict[str, Any]]:
    """(number, counterexample) of the ``number``-th counterexample (1 = the first, the default)."""
    found = _field(src, top, "counterexamples", list)
    if not found:
        raise CheckerError(
            f"{src} holds no counterexample (verdict {top.get('verdict')}): nothing to replay; only the --json of a VIOLATED run holds some"
        )
    n = 1 if number is None else number
    if not 1 <= n <= len(found):
        names = ", ".join(str(c.get("invariant")) if isinstance(c, dict) else "?" for c in found)
        give = "give --counterexample 1" if len(found) == 1 else f"give --counterexample 1 to {len(found)}"
        plural = "counterexample" if len(found) == 1 else "counterexamples"
        raise CheckerError(f"--counterexample {n}: {src} holds {len(found)} {plural} ({names}); {give}")
    return n, json_object(f"{src}: counterexamples[{n - 1}]", found[n - 1], '{"invariant": ..., "states": [...]}')


def _field(where: str, d: dict[str, Any], key: str, kind: type) -> Any:
    """``d[key]``, which must be a ``kind`` (a JSON string, list or object)."""
    value = d.get(key)
    if not isinstance(value, kind):
        what = {str: "a string", list: "a list", dict: "a JSON object"}[kind]
        shown = "missing" if key not in d else f"{value!r}"[:60]
        raise CheckerError(f"{where}: {key} = {shown} is not {what}: give the file desmon verify --json wrote, unedited there")
    return value


def format_replay_head(saved: SavedCounterexample) -> str:
    steps = len(saved.labels)
    during = f", {where_in_reaction(saved.during)}" if saved.during else ""
    return (
        f"replaying counterexample {saved.number} of {saved.count} of {saved.source}: {saved.invariant} violated after "
        f"{steps} step{'s' if steps != 1 else ''}{during} -- {saved.scenario} -- deployer {saved.deployer}"
    )


def format_divergence(saved: SavedCounterexample, index: int, replayed: dict[str, Any]) -> str:
    """One line: how state ``index`` of the replay differs from the one ``saved`` recorded."""
    recorded = saved.states[index]
    parts = [
        f"{k} {json.dumps(recorded.get(k))} recorded, {json.dumps(replayed.get(k))} replayed"
        for k in sorted(set(recorded) | set(replayed), key=str) if recorded.get(k) != replayed.get(k)
    ]
    return (
        f"  ! step {index} diverges from {saved.source}: {'; '.join(parts)} -- the scenario, the deployer or desmon "
        "changed since it was written"
    )


def format_replay_verdict(
    saved: SavedCounterexample, final: list[tuple[str, str]], found: tuple[tuple[str, str, str], ...], diverged: int | None
) -> tuple[str, bool]:
    """The invariants' verdicts on the replayed final state (``final``: the violated ones;
    ``found``: those the last reaction broke inside it, invariant first), and the verdict;
    with whether the replay still violates an invariant: its own, or (it no longer does)
    another one the file checked, which the verdict then names (no "fixed?" over a
    table of violations)."""
    bad = dict(final)
    inside = {f[0]: f for f in found}
    lines = ["invariants after the replay (on its final state; an instantaneous one also inside its last reaction):"]
    width = max(len(n) for n in saved.invariants)
    for name in saved.invariants:
        if name in bad:
            lines.append(f"  {name:<{width}}  VIOLATED: {bad[name]}")
        elif name in inside:
            lines.append(f"  {name:<{width}}  VIOLATED {where_in_reaction(inside[name][2])}: {inside[name][1]}")
        else:
            lines.append(f"  {name:<{width}}  holds")
    verdict, still = replay_verdict(saved, final, found, diverged)
    lines.append(f"verdict: {verdict}")
    return "\n".join(lines) + "\n", still


def replay_verdict(
    saved: SavedCounterexample, final: list[tuple[str, str]], found: tuple[tuple[str, str, str], ...], diverged: int | None
) -> tuple[str, bool]:
    """The verdict on a replayed counterexample (the words of ``verify --replay`` and of
    ``explore --from-json``'s banner), and whether the replay still violates an invariant."""
    bad = dict(final)
    inside = {f[0]: f for f in found}
    x = saved.invariant
    still = x in bad or x in inside
    changed = (
        f"the replay diverged from the recorded run at step {diverged} (the scenario, the deployer or desmon changed since "
        f"{saved.source} was written)" if diverged is not None else ""
    )
    others = [n for n in saved.invariants if n != x and (n in bad or n in inside)]
    if still:
        verdict = f"VIOLATED {x}: the counterexample still holds" + (f", although {changed}" if changed else ", every state as recorded")
    elif others:
        verdict = (f"VIOLATED {', '.join(others)}: the counterexample no longer violates {x}, but its replay violates "
                   + ("those" if len(others) > 1 else "that") + f" ({changed or 'every state as recorded: the file names another invariant than its run breaks, or was edited'})")
    elif changed:
        verdict = f"the counterexample no longer violates {x}: fixed? But {changed}: re-run desmon verify to check every state"
    else:
        verdict = (f"the counterexample no longer violates {x}: fixed? (every state as recorded: the deployer did the same, "
                   f"so it is the check of {x} that changed since {saved.source} was written, or the file was edited)")
    return verdict, still or bool(others)


# -- generated pytest -------------------------------------------------------------------------
_PYTEST = GENERATED_TEST_HEAD + ''': replays the shortest counterexample(s) through the real core.

The scenario and the deployer are SCENARIO and DEPLOYER below. Each step is one environment event and
the complete reaction of the DeploymentCore over the networkx repository
(desmon.verify.RepositoryRun, from the checker's initial reaction, whose starts at
INITIAL_FAILS fail); the starts listed in a step's fails fail. The test asserts the invariant is violated where the checker said.
"""

import sys

from desmon.deployment.invariants import TRANSITION_INVARIANTS, SystemView, check_invariants, get_invariants, start_findings
from desmon.loader import load_scenario
{event_imports}
{requirement_imports}
from desmon.verify import RepositoryRun
from desmon.verify.deployers import resolve_deployer

SCENARIO = {scenario_path!r}
PARAMS = {params!r}  # the -p NAME=VALUE parameters of the run that found it
DEPLOYER = {deployer!r}
#: the folder desmon verify ran in, where a module:NAME deployer was looked up first (None:
#: a file or built-in deployer); looked up there first again, from wherever this test runs
DEPLOYER_FOLDER = {folder!r}
INITIAL_ACTION = {initial_action!r}
{script_kinds}

def replay(steps, after_command=None, initial_fails=()):
    """The initial state and the state after each step; ``after_command(run, started)`` is
    called after every Start of an instance that was not running (``started``: its graph and
    platform) and every Stop (``started``: None)."""
    if DEPLOYER_FOLDER is not None and DEPLOYER_FOLDER not in sys.path:
        sys.path.insert(0, DEPLOYER_FOLDER)
    run = RepositoryRun(load_scenario(SCENARIO, PARAMS), resolve_deployer(DEPLOYER), initial_fails=initial_fails)
    assert run.bounds.start_action(run.scenario) == INITIAL_ACTION, "not the checker's initial state"
    if after_command is not None:
        control, start, stop = run.control, run.control.start, run.control.stop

        def audited_start(graph, platform):
            restart = (graph, platform) in control.running  # (a no-op: it changes nothing to audit)
            ok = start(graph, platform)
            if not restart:
                after_command(run, (graph, platform) if ok else None)
            return ok

        def audited_stop(graph, platform):
            ok = stop(graph, platform)
            after_command(run, None)
            return ok

        control.start, control.stop = audited_start, audited_stop
        if not steps:  # a counterexample of 0 steps: the initial reaction, judged as a whole
            after_command(run, None)
    views = [run.view()]  # (a counterexample of 0 steps: the initial state itself)
    for i, (event, fails) in enumerate(steps, 1):
        run.at_step = i  # (an audit judges the step the checker named, not an earlier one)
        run.step(event, fails)
        if after_command is not None:
            after_command(run, None)  # the reaction's moves are judged once it is complete, too
        views.append(run.view())
    return views
'''

_CASE = '''

def test_{name}():
    """{invariant} violated after {length} step(s){during}."""
    steps = [
{steps}
    ]
    views = replay(steps, initial_fails={initial_fails!r})
    bad = check_invariants(views[-1], get_invariants([{invariant!r}]))
    assert bad, "the counterexample no longer violates {invariant}"
    for view in views[:-1]:
        assert not check_invariants(view, get_invariants([{invariant!r}]))
'''


def counterexample_pytest(
    r: CheckResult, scenario_path: str, initial_action: str | None, params: dict[str, str] | None = None
) -> str:
    from desmon.verify.deployers import module_folder, portable_spec

    src = _PYTEST.format(
        scenario_path=scenario_path, params=dict(params or {}), deployer=portable_spec(r.deployer), initial_action=initial_action,
        folder=module_folder(r.deployer),
        event_imports=_event_imports(), requirement_imports=_requirement_imports(), script_kinds=_script_kinds(),
    )
    for c in r.counterexamples:
        steps = []
        for s in c.steps[1:]:
            fails = _fail_indices(s)
            steps.append(f"        ({s.event!r}, {fails!r}),{_step_comment(s)}")
        during = f" (during the reaction, after {c.during})" if c.during else ""
        case = _CASE_DURING if c.during else _CASE  # (during: an instantaneous violation the final stable state may have repaired)
        src += case.format(
            name=c.invariant.replace("-", "_"), invariant=c.invariant, length=c.length, during=during, steps="\n".join(steps),
            initial_fails=c.initial_fails,
        )
    return src


def _importable(cls: type) -> bool:
    """Whether a fresh process imports ``cls`` from its module: not a class a scenario script (or a
    helper beside it, dropped after the load) defined, whose module is gone once the script ran."""
    return cls.__module__ in sys.modules


def _event_imports() -> str:
    """The import lines of every event class (the registry), by module, names sorted; an event
    kind a scenario script defined is looked up once the scenario is loaded (:func:`_script_kinds`)."""
    modules: dict[str, list[str]] = {}
    for cls in Event.kinds():
        if _importable(cls):
            modules.setdefault(cls.__module__, []).append(cls.__name__)
    return "\n".join(f"from {m} import (\n    {', '.join(sorted(names))},\n)" for m, names in modules.items())


def _requirement_imports() -> str:
    """The import lines of the generated test for every requirement kind (the events'
    reprs name them), read from the registry: desmon's own kinds, Option and Preference
    from :mod:`desmon.model.requirements`, a kind defined elsewhere from its module (one a
    scenario script defined: :func:`_script_kinds`)."""
    from desmon.model.kinds import requirement_class, requirement_kinds

    by_module: dict[str, set[str]] = {"desmon.model.requirements": {"Option", "Preference"}}
    for word in requirement_kinds():
        cls = requirement_class(word)
        if _importable(cls):  # type: ignore[arg-type]
            by_module.setdefault(cls.__module__, set()).add(cls.__name__)  # type: ignore[union-attr]
    return "\n".join(f"from {module} import {', '.join(sorted(names))}" for module, names in by_module.items())


def _script_kinds() -> str:
    """The lines that give the generated test the requirement and event kinds a scenario script
    defined: no module of theirs to import, they are registered again when the scenario loads
    (a kind of another script loaded in the same process is None there, and unused)."""
    from desmon.model.kinds import requirement_class, requirement_kinds

    lines = [f"{c.__name__} = requirement_class({w!r})" for w in requirement_kinds() if not _importable(c := requirement_class(w))]  # type: ignore[arg-type]
    lines += [f"{c.__name__} = Event.of_kind({c.kind!r})" for c in Event.kinds() if not _importable(c)]
    if not lines:
        return ""
    head = "\nfrom desmon.model.events import Event\nfrom desmon.model.kinds import requirement_class\n\nload_scenario(SCENARIO, PARAMS)  # (registers the kinds its script defines)\n"
    return head + "\n".join(lines) + "\n"


_CASE_DURING = '''

def test_{name}():
    """{invariant} violated after {length} step(s){during}: replayed with an audit after every start."""
    steps = [
{steps}
    ]
    bad = []

    def audit(run, started):
        if getattr(run, "at_step", 0) != len(steps):  # an earlier step: the checker named the last one
            return
        if not steps and any(f[0] == {invariant!r} for f in run.initial_found):
            bad.extend(f[:2] for f in run.initial_found if f[0] == {invariant!r})  # broken inside the initial reaction, after a start
            return
        if {invariant!r} == "no-flapping" or {invariant!r} in TRANSITION_INVARIANTS:  # judged on the reaction
            bad.extend(run.violations(get_invariants([{invariant!r}])))
            return
        if started is not None:  # (judged on what the start changed, as every engine judges it)
            view = SystemView(run.query.platform_states(), run.core.specs(), frozenset(), ())
            bad.extend(start_findings(view, get_invariants([{invariant!r}]), *started))

    replay(steps, after_command=audit, initial_fails={initial_fails!r})
    assert bad, "the counterexample no longer violates {invariant}"
'''


def _step_comment(s: Step) -> str:
    """`` # ...`` naming the starts the checker chose to fail and the refused ones, or ""."""
    said = [f"{start} fails (chosen)" for start in s.failed_starts] + [f"{start} refused: {why}" for start, why in s.refused]
    return f"  # {'; '.join(said)}" if said else ""


def _fail_indices(s: Step) -> tuple[int, ...]:
    return s.fail_indices


def run_script(scenario: "object", argv: "list[str] | None" = None) -> int:
    """What ``python scenarios/<name>.py [paper]`` does: check every invariant with the
    named deployer (default ``desmon``), print the report, return the exit code."""
    import sys

    from desmon.verify.checker import Checker

    args = sys.argv[1:] if argv is None else argv
    result = Checker(scenario, args[0] if args else "desmon").run(keep_going=True)  # type: ignore[arg-type]
    print(format_result(result), end="")
    return result.exit_code
