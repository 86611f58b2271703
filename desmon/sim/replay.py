"""Deterministic replay of a scenario's timeline, with no latency and no signals.

The simplest engine: each timed event goes through the deployment core at once, on
the networkx repository, and the named invariants are audited after every reaction (the
reaction's transition properties, then the state it left, as ``desmon run`` audits them).
The paper's t0..t3 walk-through is this replay of ``scenarios/coffee_handover.py``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

import networkx as nx

from desmon.deployment.guard import DeployerFault, Guard
from desmon.deployment.control import repository_control
from desmon.deployment.core import DeploymentCore, stamp
from desmon.deployment.invariants import INSTANT_INVARIANTS, check_invariants, get_invariants, start_findings
from desmon.deployment.run import RunContext, run_context
from desmon.deployment.monitor import Stimulus
from desmon.deployment.validity import ScalarChecks
from desmon.deployment.ports import Command, ErrorRecord, Start
from desmon.model.checks import seconds_text, visible
from desmon.model.events import Event
from desmon.model.scenario import Scenario
from desmon.repository import labels as L
from desmon.repository.facts import ImmediateControl, RepositoryInsert, load_model
from desmon.repository.query import RepositoryQuery
from desmon.repository.store import Repository

__all__ = ["ReplayStep", "Replay", "replay", "deployment_edges", "format_replay"]


@dataclass(frozen=True, slots=True)
class ReplayStep:
    """One timeline event and the system's complete reaction to it."""

    time: float
    label: str
    event: Event
    stimulus: Stimulus
    commands: tuple[tuple[Command, bool | None], ...]
    errors: tuple[ErrorRecord, ...]
    deployments: tuple[tuple[str, str], ...]
    standing: frozenset[str]
    violations: tuple[tuple[str, str], ...]
    #: the starts of ``commands`` the Control rules refused: ``(graph, platform) -> reason``
    #: (every other failed start failed by ``start_fails``)
    refused: tuple[tuple[tuple[str, str], str], ...] = ()
    #: the errors standing before the step
    standing_before: frozenset[str] = frozenset()
    #: the repository's :attr:`~desmon.repository.store.Repository.version` after the step
    #: (``repo.snapshot(upto=version)``: the graph then, before a later event of the same time)
    version: int = 0


@dataclass
class Replay:
    scenario: Scenario
    deployer: str
    repo: Repository
    control: ImmediateControl
    steps: list[ReplayStep] = field(default_factory=list)
    #: the repository's version before the first step (the model and the initial facts loaded)
    start_version: int = 0

    @property
    def errors(self) -> list[ErrorRecord]:
        return [e for s in self.steps for e in s.errors]

    @property
    def violations(self) -> list[tuple[float, str, str]]:
        return [(s.time, n, m) for s in self.steps for n, m in s.violations]

    def graph_after(self, steps: int) -> nx.MultiDiGraph:
        """The repository graph after the first ``steps`` steps (0: before the first), as a
        copy: of two events at one time, the first's graph does not show the second."""
        return self.repo.snapshot(upto=self.steps[steps - 1].version if steps else self.start_version)


def deployment_edges(g: nx.MultiDiGraph) -> set[tuple[str, str, str]]:
    """The deployment-related edges of a snapshot as (source, label, target) triples (Fig. 5)."""
    return {(s, d["label"], t) for s, t, d in g.edges(data=True) if d["label"] in L.DEPLOYMENT_EDGES}


def _start_failed(fault: DeployerFault, control: Any) -> bool:
    """Whether a start of the failed reaction failed, not refused by the Control rules (then
    a first reaction that failed is a state the run reached, as the checker says)."""
    failed = [c for c, ok in (fault.log.commands if fault.log else ()) if type(c) is Start and ok is False]
    return any(control.refuse(c.graph, c.platform) is None for c in failed)


def replay(
    scenario: Scenario,
    deployer: str = "desmon",
    *,
    start_fails: Callable[[str, str], bool] | None = None,
    guard: Guard | None = None,
    run: RunContext | None = None,
) -> Replay:
    """Run ``scenario.timeline`` through the deployment core (under ``guard``, the run's
    guard: :mod:`desmon.deployment.guard`, or the whole ``run`` context,
    :mod:`desmon.deployment.run`); returns every step."""
    context = run_context(run, guard).with_checks(ScalarChecks)
    now = [scenario.timeline[0].time if scenario.timeline else 0.0]
    repo = Repository(clock=lambda: now[0])
    load_model(repo, scenario.model)
    query = RepositoryQuery(repo, context.checks)  # the run's memoised checks
    control = repository_control(repo, scenario.model, start_fails)
    core = DeploymentCore(scenario.model, query, RepositoryInsert(repo, scenario.model.robot), deployer, run=context)
    for event in scenario.initial:
        core.observe(event)
    result = Replay(scenario, core.deployer.name, repo, control, start_version=repo.version)
    instant = get_invariants(INSTANT_INVARIANTS)
    for te in scenario.timeline:
        now[0] = te.time
        before = core.standing
        during: list[tuple[str, str]] = []  # the reaction's instantaneous violations, the first of each, as the checker reports them

        def watch(verb: str, graph: str, platform: str) -> None:
            if len(during) == len(instant) or verb != "start":  # (a stop breaks none of them)
                return
            seen = {d for d, _m in during}
            for name, msg in start_findings(core.view(), instant, graph, platform):
                if name not in seen:
                    during.append((name, f"{msg} (during the reaction, right after `{verb} {graph} on {platform}`)"))

        control.after = watch
        try:
            stim, log = core.step(te.event, control)
        except DeployerFault as fault:  # its first reaction: the deployer cannot run at all (exit 2), else CRASHED
            fault.initial = not result.steps and not _start_failed(fault, control)
            fault.args = (f"at t={te.time:g} s ({te.label or te.event}), {fault.args[0]}",)
            raise
        finally:
            control.after = None
        # the Control rules read facts a reaction does not change: asked after it, they give
        # the reason each refused start of the reaction was refused for
        refuse = control.refuse
        refused = tuple(
            ((c.graph, c.platform), why)
            for c, ok in log.commands
            if type(c) is Start and ok is False and refuse is not None and (why := refuse(c.graph, c.platform)) is not None
        )
        history = sum(1 for _ in repo.edges(L.DEPLOYMENT_HISTORY))
        view = core.view(running=tuple(sorted(control.running)), stops=control.stops, history=history)
        result.steps.append(
            ReplayStep(
                time=te.time,
                label=te.label,
                event=te.event,
                stimulus=stim,
                commands=tuple(log.commands),
                errors=tuple(stamp(e, te.time) for e in log.errors),
                deployments=query.deployments(),
                standing=core.standing,
                # its transition properties first, as the run reports them, then those broken
                # inside the reaction (not again if its end state breaks them too)
                violations=(*core.findings, *during, *[v for v in check_invariants(view) if all(v[0] != d for d, _m in during)]),
                refused=refused,
                standing_before=before,
                version=repo.version,
            )
        )
    return result


def _outcome(step: ReplayStep, cmd: Command, ok: bool) -> str:
    if ok:
        return "ok"
    if type(cmd) is not Start:
        return "FAILED"
    why = dict(step.refused).get((cmd.graph, cmd.platform))
    return f"REFUSED by the Control rules: {why}" if why is not None else "FAILED (a start failure of the environment)"


def format_replay(r: Replay) -> str:
    """The replay as numbered steps: event, decisions (a failed start refused by the
    Control rules, with the rule's reason, or failed by the environment), the errors the
    reaction raised, the errors standing after it, deployment edges."""
    lines = [f"{r.scenario.name} -- deployer {r.deployer}", ""]
    for i, step in enumerate(r.steps, 1):
        head = f"{step.label + ' ' if step.label else ''}t={seconds_text(step.time)}s  {step.event}"
        lines.append(head)
        for cmd, ok in step.commands:
            if ok is None:
                continue
            lines.append(f"    {cmd}: {_outcome(step, cmd, ok)}")
        for err in step.errors:
            lines.append(f"    raised ERROR {err.kind}: {err.graph}" + (f" on {err.platform}" if err.platform else ""))
            for reason in visible(err.detail).splitlines():
                lines.append(f"        {reason}")
        if step.errors or step.standing != step.standing_before:
            lines.append("    standing errors: " + (", ".join(sorted(step.standing)) or "none"))
        snap = r.graph_after(i)
        for s, label, t in sorted(deployment_edges(snap), key=lambda e: (e[1], e[0], e[2])):
            if label == L.HAS_DEVICE:
                continue
            lines.append(f"    {s} -[{label}]-> {t}")
        devices = sorted(t for s, label, t in deployment_edges(snap) if label == L.HAS_DEVICE)
        lines.append(f"    HAS_DEVICE: {len(devices)} edges" + (f" (no {', '.join(sorted(_missing(r, snap)))})" if _missing(r, snap) else ""))
        for name, msg in step.violations:
            lines.append(f"    INVARIANT VIOLATED {name}: {msg}")
        lines.append("")
    return "\n".join(lines).rstrip() + "\n"


def _missing(r: Replay, snap: nx.MultiDiGraph) -> list[str]:
    present = {t for _s, label, t in deployment_edges(snap) if label == L.HAS_DEVICE}
    return [f"{L.DEVICE}:{d.name}" for d in r.scenario.model.devices if f"{L.DEVICE}:{d.name}" not in present]
