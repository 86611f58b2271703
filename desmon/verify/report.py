"""Presenting checker results: text report, numbered traces, JSON (ITF-like), a pytest."""

from __future__ import annotations

from typing import Any

from desmon.model.events import (
    ActionChange, DeviceFail, DeviceRepair, Event, LoadChange, PlatformDown, PlatformJoin, PlatformLeave, PlatformUp, RequirementChange,
)
from desmon.verify.search import NOT_CHECKED, CheckResult
from desmon.verify.trace import Counterexample, Step
from desmon.verify.state import Key

__all__ = ["format_result", "format_trace", "result_to_json", "counterexample_pytest", "event_to_json", "event_from_json", "key_to_json"]


def format_trace(steps: tuple[Step, ...] | list[Step], *, indent: str = "  ") -> str:
    """Numbered steps ``event -> what changed``."""
    lines = []
    for s in steps:
        changes = "; ".join(s.changes)
        lines.append(f"{indent}{s.index:>2}. {s.title()} -> {changes}")
    return "\n".join(lines)


def format_counterexample(c: Counterexample) -> str:
    head = f"VIOLATED {c.invariant} after {c.length} step{'s' if c.length != 1 else ''} (shortest)"
    if c.during:
        head += f", during the reaction, right after `{c.during}`"
    return f"{head}:\n{format_trace(c.steps)}\n  => {c.invariant}: {c.message}"


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
        f"states: {r.states:,}  transitions: {r.transitions:,}  depth: {r.depth}  time: {r.seconds:.2f}s  "
        f"{r.states_per_second:,.0f} states/s  {r.transitions_per_second:,.0f} transitions/s  peak memory: {r.peak_mb:.0f} MB"
        + (f" (+ {r.workers} workers, each at most {r.peak_workers_mb:.0f} MB)" if r.worker_levels else "")
    )
    if r.engine == "table":
        lines.append(f"engine: table ({r.records:,} recorded runs of the core and the invariants, replayed for the rest)")
    else:
        lines.append("engine: direct" + (f" ({r.engine_note})" if r.engine_note else ""))
    kinds = sorted(set(r.enabled) | set(r.new_states))
    if kinds:
        lines.append("events (enabled / new states): " + ", ".join(f"{k} {r.enabled[k]:,}/{r.new_states[k]:,}" for k in kinds))
        dead = [k for k in kinds if not r.changed[k]]
        if dead and r.verdict == "HOLDS":
            lines.append("  warning: dead event kinds (never changed the state; a scenario bug?): " + ", ".join(dead))
    if r.rules:
        lines.append("selector contexts exercised: " + ", ".join(f"{c or '(none)'} {n:,}" for c, n in sorted(r.rules.items(), key=lambda x: str(x[0]))))
    if r.branches:
        lines.append("deployer branches: " + ", ".join(f"{b} {n:,}" for b, n in sorted(r.branches.items())))
    return "\n".join(lines) + "\n"


# -- JSON ------------------------------------------------------------------------------------
def event_to_json(e: Event | None) -> dict[str, Any] | None:
    if e is None:
        return None
    if isinstance(e, ActionChange):
        return {"kind": "action", "action": e.action}
    if isinstance(e, (DeviceFail, DeviceRepair)):
        return {"kind": "device_fail" if isinstance(e, DeviceFail) else "device_repair", "device": e.device}
    if isinstance(e, (PlatformDown, PlatformUp)):
        return {"kind": "platform_down" if isinstance(e, PlatformDown) else "platform_up", "platform": e.platform}
    if isinstance(e, (PlatformJoin, PlatformLeave)):
        return {"kind": "platform_join" if isinstance(e, PlatformJoin) else "platform_leave", "platform": e.platform}
    if isinstance(e, RequirementChange):
        return {
            "kind": "requirements", "graph": e.graph, "label": e.label,
            "add": [r.describe() for r in e.add], "remove": [r.describe() for r in e.remove],
        }
    return {"kind": "load", "platform": e.platform, "amount": e.amount, "resource": e.resource}


def event_from_json(d: dict[str, Any]) -> Event:
    k = d["kind"]
    if k == "action":
        return ActionChange(d["action"])
    if k == "device_fail":
        return DeviceFail(d["device"])
    if k == "device_repair":
        return DeviceRepair(d["device"])
    if k == "platform_down":
        return PlatformDown(d["platform"])
    if k == "platform_up":
        return PlatformUp(d["platform"])
    if k in ("platform_join", "platform_leave"):
        return (PlatformJoin if k == "platform_join" else PlatformLeave)(d["platform"])
    if k == "requirements":
        from desmon.errors import CheckerError

        raise CheckerError(
            f"a requirement change of {d.get('graph')!r} is written in the JSON by its description only: take the event "
            "from the scenario's Bounds.requirement_changes (the --pytest file replays it exactly)"
        )
    return LoadChange(d["platform"], d["amount"], d.get("resource", "memory"))


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
            {"step": s.index, "event": event_to_json(s.event), "failed_starts": list(s.failed_starts), "changes": list(s.changes), "state": key_to_json(s.key)}
            for s in c.steps
        ],
    }


def result_to_json(r: CheckResult) -> dict[str, Any]:
    return {
        "scenario": r.scenario,
        "deployer": r.deployer,
        "verdict": r.verdict,
        "reason": r.reason,
        "states": r.states,
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
        "counterexamples": [counterexample_to_json(c) for c in r.counterexamples],
    }


# -- generated pytest -------------------------------------------------------------------------
_PYTEST = '''"""Generated by `desmon verify`: replays the shortest counterexample(s) through the real core.

Scenario {scenario_path!r}, deployer {deployer!r}. Each step is one environment event and
the complete reaction of the DeploymentCore over the networkx repository
(desmon.verify.RepositoryRun, from the checker's initial reaction); the starts listed in
FAILS fail. The test asserts the invariant is violated where the checker said.
"""

from desmon.deployment.invariants import SystemView, check_invariants, get_invariants
from desmon.loader import load_scenario
from desmon.model.events import (
    ActionChange, DeviceFail, DeviceRepair, LoadChange, PlatformDown, PlatformJoin, PlatformLeave, PlatformUp, RequirementChange,
)
from desmon.model.requirements import Attribute, Capacity, Maximum, Minimum, Option, Preference, Quantity, Selection
from desmon.verify import RepositoryRun
from desmon.verify.deployers import resolve_deployer

SCENARIO = {scenario_path!r}
PARAMS = {params!r}  # the -p NAME=VALUE parameters of the run that found it
DEPLOYER = {deployer!r}
INITIAL_ACTION = {initial_action!r}


def replay(steps, after_command=None):
    """The states after each step; ``after_command(run)`` is called after every Start/Stop."""
    run = RepositoryRun(load_scenario(SCENARIO, PARAMS), resolve_deployer(DEPLOYER))
    assert run.bounds.start_action(run.scenario) == INITIAL_ACTION, "not the checker's initial state"
    if after_command is not None:
        control, start, stop = run.control, run.control.start, run.control.stop

        def audited_start(graph, platform):
            ok = start(graph, platform)
            after_command(run)
            return ok

        def audited_stop(graph, platform):
            ok = stop(graph, platform)
            after_command(run)
            return ok

        control.start, control.stop = audited_start, audited_stop
    views = []
    for event, fails in steps:
        run.step(event, fails)
        if after_command is not None:
            after_command(run)  # the reaction's moves are judged once it is complete, too
        views.append(run.view())
    return views
'''

_CASE = '''

def test_{name}():
    """{invariant} violated after {length} step(s){during}."""
    steps = [
{steps}
    ]
    views = replay(steps)
    bad = check_invariants(views[-1], get_invariants([{invariant!r}]))
    assert bad, "the counterexample no longer violates {invariant}"
    for view in views[:-1]:
        assert not check_invariants(view, get_invariants([{invariant!r}]))
'''


def counterexample_pytest(
    r: CheckResult, scenario_path: str, initial_action: str | None, params: dict[str, str] | None = None
) -> str:
    from desmon.verify.deployers import portable_spec

    src = _PYTEST.format(
        scenario_path=scenario_path, params=dict(params or {}), deployer=portable_spec(r.deployer), initial_action=initial_action
    )
    for c in r.counterexamples:
        steps = []
        for s in c.steps[1:]:
            fails = _fail_indices(s)
            steps.append(f"        ({s.event!r}, {fails!r}),")
        during = f" (during the reaction, after {c.during})" if c.during else ""
        if c.during:
            # an instantaneous violation: the final stable state may have repaired it
            src += _CASE_DURING.format(name=c.invariant.replace("-", "_"), invariant=c.invariant, length=c.length, during=during, steps="\n".join(steps))
        else:
            src += _CASE.format(name=c.invariant.replace("-", "_"), invariant=c.invariant, length=c.length, during=during, steps="\n".join(steps))
    return src


_CASE_DURING = '''

def test_{name}():
    """{invariant} violated after {length} step(s){during}: replayed with an audit after every command."""
    steps = [
{steps}
    ]
    bad = []

    def audit(run):
        if {invariant!r} == "no-flapping":
            bad.extend(run.violations(get_invariants([{invariant!r}])))
            return
        view = SystemView(run.query.platform_states(), run.core.specs(), frozenset(), ())
        bad.extend(check_invariants(view, get_invariants([{invariant!r}])))

    replay(steps, after_command=audit)
    assert bad, "the counterexample no longer violates {invariant}"
'''


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
