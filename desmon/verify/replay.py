"""Replaying the checker's events on the networkx repository (no hypothesis needed).

:func:`initial_reaction` is *the* initial state of every run the checker compares with:
the scenario's initial facts, then the system's first reaction (the start action of the
bounds, or a context reaction). :class:`Checker.initial <desmon.verify.checker.Checker>`
runs it on the state store, :class:`RepositoryRun` on a fresh networkx repository; the
fuzzer, ``--plot``, the generated pytest of ``desmon verify --pytest`` and ``desmon
verify --replay`` (:meth:`RepositoryRun.trace`) step a :class:`RepositoryRun` event by event.
"""

from __future__ import annotations

from typing import Any, Container, Iterator, Sequence

from desmon.errors import CheckerError
from desmon.deployment.control import repository_refusal
from desmon.deployment.core import DeploymentCore, run_sync
from desmon.deployment.guard import DeployerFault, Guard
from desmon.deployment.deployer import Deployer
from desmon.deployment.invariants import INVARIANTS, Invariant, check_invariants, get_invariants, start_findings
from desmon.deployment.run import RunContext, run_context
from desmon.deployment.monitor import Stimulus
from desmon.deployment.validity import ScalarChecks
from desmon.deployment.ports import ControlPort
from desmon.model.events import ActionChange, Event
from desmon.model.scenario import Scenario
from desmon.model.system import SystemModel
from desmon.repository import labels as L
from desmon.repository.facts import ImmediateControl, RepositoryInsert, load_model
from desmon.repository.query import RepositoryQuery
from desmon.repository.store import Repository
from desmon.verify.bounds import Bounds, bounds_of
from desmon.verify.state import Key
from desmon.verify.trace import Label, Step, initial_step, make_step, reaction_findings

__all__ = ["initial_reaction", "first_reaction_fault", "ScriptedControl", "RepositoryRun", "repository_key"]


def initial_reaction(core: DeploymentCore, scenario: Scenario, bounds: Bounds, control: ControlPort, fails: tuple[int, ...] = ()) -> Any:
    """The scenario's initial facts, then the system's first reaction through ``control``
    (whose starts fail as it decides: ``fails``, the indices of the starts the Control rules
    allow that fail); returns the reaction's StepLog. A deployer that fails in it cannot
    run at all when no start failed (a DeployerFault marked ``initial``: exit 2); with
    ``fails`` it failed in a reachable state (a DeployerFault naming them: CRASHED)."""
    for ev in scenario.initial:
        core.observe(ev)
    act = bounds.start_action(scenario)
    try:
        if act is not None:
            return core.step(ActionChange(act), control, force=True)[1]
        log = run_sync(core.reaction(Stimulus(context_changed=True)), control)
        core.settle(e.graph for e in log.errors)
        return log
    except DeployerFault as fault:
        context = core.query.context()
        where = f"action {act}" if act is not None else f"context {context}"
        if not fails:  # no state to show a path to: the deployer cannot run at all (exit 2)
            raise first_reaction_fault(core.deployer.name, where, fault) from None
        # it failed only because a start the checker chose failed: a reachable state (CRASHED)
        where += ", with " + ", ".join(f"start #{i + 1}" for i in fails) + " failing"
        out = DeployerFault(f"deployer {core.deployer.name}, reacting to the initial state ({where}): {fault.what or fault}")
        out.stimulus, out.log, out.cause, out.what = fault.stimulus, fault.log, fault.cause, fault.what
        raise out from None


def first_reaction_fault(name: str, where: str, fault: DeployerFault) -> DeployerFault:
    """``fault`` of the initial reaction, said as what it means: the deployer cannot run at all."""
    what = str(fault.what or fault)
    said = what if what.startswith("its ") else f"it {what}"  # ("it its reaction returned ...": its own subject)
    out = DeployerFault(f"deployer {name} cannot run at all: reacting to the initial state ({where}), {said}")
    out.stimulus, out.log, out.cause, out.what = fault.stimulus, fault.log, fault.cause, fault.what
    out.initial = True
    return out


def _unissued(whose: str, fails: tuple[int, ...], issued: int) -> str:
    """Why a replay's failing start indices no longer apply: the reaction issues fewer real starts."""
    return (
        f"{whose} fail_indices {list(fails)} fail start #{max(fails) + 1} of the reaction, which issues "
        f"{issued} real start{'s' if issued != 1 else ''} now"
    )


class ScriptedControl(ImmediateControl):
    """The Control rules on the repository, where the real starts the rules do not refuse
    (not the no-op restarts) fail at given indices, as the checker's outcome prefix says."""

    def __init__(self, repo: Repository, model: SystemModel) -> None:
        super().__init__(repo, self._scripted_fail, repository_refusal(repo, model))
        self.fail_at: tuple[int, ...] = ()
        self.n = 0

    def arm(self, fails: tuple[int, ...]) -> None:
        self.fail_at, self.n = fails, 0

    def _scripted_fail(self, graph: str, platform: str) -> bool:
        i, self.n = self.n, self.n + 1
        return i in self.fail_at



def repository_key(repo: Repository, core: DeploymentCore) -> Key:
    """The checker's key of a networkx repository's current state, with ``core``'s standing
    errors and current specifications: how a replay, or a simulation at a quiescent
    point, is compared with the states the checker reaches."""
    failed = tuple(sorted(d["name"] for _n, d in repo.nodes(L.DEVICE) if not d["working"]))
    down = tuple(sorted(d["name"] for _n, d in repo.nodes(L.PLATFORM) if not d["up"]))
    loads = tuple((d["name"], tuple(sorted(d["load"].items()))) for _n, d in repo.nodes(L.PLATFORM) if d["load"])
    declared = {s.graph: s.requirements for s in core.model.specs}
    specs = tuple(sorted((s.graph, s.requirements) for s in core.specs() if s.requirements != declared[s.graph]))
    return Key(core.query.context(), failed, down, loads, core.query.deployments(), tuple(sorted(core.standing)), specs)


class RepositoryRun:
    """The deployment core on a fresh networkx repository, stepped event by event (under
    ``guard``, or the whole ``run`` context: :mod:`desmon.deployment.run`), from the initial
    state whose first reaction failed the starts at ``initial_fails`` (indices among those
    the Control rules allow: the checker's choice). Indices beyond the starts that reaction
    issues are refused (a saved trace the scenario no longer matches), or dropped with
    ``unissued_fails_drop`` (a fuzzer's draw)."""

    def __init__(
        self, scenario: Scenario, deployer: str | Deployer = "desmon", bounds: Bounds | None = None, guard: Guard | None = None,
        run: RunContext | None = None, initial_fails: tuple[int, ...] = (), unissued_fails_drop: bool = False,
    ) -> None:
        self.scenario = scenario
        self.run_context = run_context(run, guard).with_checks(ScalarChecks)
        self.bounds = bounds or bounds_of(scenario)
        self.repo = Repository()
        load_model(self.repo, scenario.model)
        self.query = RepositoryQuery(self.repo, self.run_context.checks)  # the run's memoised checks
        self.control = ScriptedControl(self.repo, scenario.model)
        self.core = DeploymentCore(scenario.model, self.query, RepositoryInsert(self.repo, scenario.model.robot), deployer, run=self.run_context)
        found = self._watch(get_invariants(list(self.bounds.instantaneous)))
        #: the starts the first reaction failed by the checker's choice (indices among those the rules allow)
        self.initial_fails = tuple(initial_fails)
        self.control.arm(self.initial_fails)
        try:
            self.initial_log = initial_reaction(self.core, scenario, self.bounds, self.control, self.initial_fails)
        finally:
            self.control.after = None
        if self.initial_fails and max(self.initial_fails) >= self.control.n:  # (a fuzz draw: dropped; a saved trace: refused)
            if not unissued_fails_drop:
                raise CheckerError(_unissued("the initial reaction's", self.initial_fails, self.control.n))
            self.initial_fails = tuple(i for i in self.initial_fails if i < self.control.n)
        #: the instantaneous invariants the initial reaction broke after a start, the
        #: first violation of each, as ``(invariant, message, after what)`` (the checker
        #: judges them as any reaction's)
        self.initial_found: tuple[tuple[str, str, str], ...] = tuple(found)
        #: the first of them, or None (what a test generated by an earlier desmon reads)
        self.initial_instant: tuple[str, str, str] | None = found[0] if found else None

    def _watch(self, instant: tuple[Invariant, ...]) -> list[tuple[str, str, str]]:
        """Audit ``instant`` after every start from now on (:func:`~desmon.deployment.invariants.start_findings`):
        the first violation of each is appended to the list returned, in order (the caller
        sets ``control.after`` back to None)."""
        found: list[tuple[str, str, str]] = []

        def audit(verb: str, graph: str, platform: str) -> None:
            if len(found) == len(instant) or verb != "start":  # (a stop breaks none of them)
                return
            seen = {f[0] for f in found}
            for name, msg in start_findings(self.core.view(), instant, graph, platform):
                if name not in seen:
                    found.append((name, msg, f"{verb} {graph} on {platform}"))

        self.control.after = audit if instant else None
        return found

    def step(self, event: Event, fails: tuple[int, ...] = ()):  # type: ignore[no-untyped-def]
        """``event`` and the complete reaction; the ``fails``-th real starts of it fail."""
        self.control.arm(fails)
        return self.core.step(event, self.control)

    def step_watching(self, event: Event, fails: tuple[int, ...], instant: tuple[Invariant, ...]):  # type: ignore[no-untyped-def]
        """:meth:`step`, and the first violation of an ``instant`` invariant after a start or
        stop inside its reaction, as ``(invariant, message, after what)``, or None (the
        checker watches the same inside a reaction: :class:`~desmon.verify.bounds.Bounds`'
        ``instantaneous``)."""
        result, found = self._step_finding_each(event, fails, instant)
        return result, (found[0] if found else None)

    def _step_finding_each(self, event: Event, fails: tuple[int, ...], instant: tuple[Invariant, ...]):  # type: ignore[no-untyped-def]
        """:meth:`step`, and the first violation of each ``instant`` invariant after a start or
        stop inside its reaction, in order."""
        found = self._watch(instant)
        try:
            result = self.step(event, fails)
        finally:
            self.control.after = None
        return result, tuple(found)

    def key(self) -> Key:
        """The checker's key of the repository's current state (for cross-checks)."""
        return repository_key(self.repo, self.core)

    def view(self) -> Any:
        """The SystemView of every invariant, ``history`` included (running list, stops, edges)."""
        history = sum(1 for _ in self.repo.edges(L.DEPLOYMENT_HISTORY))
        return self.core.view(running=tuple(sorted(self.control.running)), stops=self.control.stops, history=history)

    def violations(self, invariants=None):  # type: ignore[no-untyped-def]
        """The invariants on the current view, plus the last reaction's moves that broke
        ``no-flapping`` (its transition half, noted by the core)."""
        out = check_invariants(self.view(), invariants)
        names = {i.name for i in invariants} if invariants is not None else INVARIANTS
        for name, msg in self.core.findings:
            if name in names and not any(n == name for n, _m in out):
                out.append((name, msg))
        return out

    def trace(
        self, labels: Sequence[Label], instant: tuple[Invariant, ...] = (), transitions: Container[str] = ()
    ) -> Iterator[tuple[Step, tuple[tuple[str, str, str], ...]]]:
        """The current state as step 0, then each label stepped, as the checker's
        counterexample shows it. With each step, what its reaction broke inside it, as
        ``(invariant, message, after what)``, the first violation of each: the ``instant``
        invariants after a start, then the transition properties among
        ``transitions`` (``no-flapping``, ``errors-justified``, ``preferred-when-possible``)
        it broke as a whole. The checker watches the same (:class:`~desmon.verify.bounds.Bounds`'
        ``instantaneous``); step 0 carries what the initial reaction broke (call this on a
        run that has not stepped yet)."""
        watched = {i.name for i in instant}
        first = tuple(f for f in self.initial_found if f[0] in watched)
        step0 = initial_step(self.key(), self.initial_log, self.initial_fails, self.control.refuse)
        yield step0, reaction_findings(first, self.core.findings_of(transitions, True) if transitions else [])
        for i, (event, fails) in enumerate(labels, start=1):
            prev = self.key()
            (_stim, log), during = self._step_finding_each(event, fails, instant)
            if fails and max(fails) >= self.control.n:  # a failing start the reaction no longer issues
                raise CheckerError(_unissued("its", fails, self.control.n))
            found = reaction_findings(during, self.core.findings_of(transitions, True) if transitions else [])
            yield make_step(i, prev, event, self.key(), log, fails, self.control.refuse), found
