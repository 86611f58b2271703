"""Replaying the checker's events on the networkx repository (no hypothesis needed).

:func:`initial_reaction` is *the* initial state of every run the checker compares with:
the scenario's initial facts, then the system's first reaction (the start action of the
bounds, or a context reaction). :class:`Checker.initial <desmon.verify.checker.Checker>`
runs it on the state store, :class:`RepositoryRun` on a fresh networkx repository; the
fuzzer, ``--plot`` and the generated pytest of ``desmon verify --pytest`` step a
:class:`RepositoryRun` event by event.
"""

from __future__ import annotations

from typing import Any

from desmon.deployment.control import repository_refusal
from desmon.deployment.core import DeploymentCore, run_sync
from desmon.deployment.deployer import Deployer
from desmon.deployment.invariants import check_invariants
from desmon.deployment.monitor import Stimulus
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

__all__ = ["initial_reaction", "ScriptedControl", "RepositoryRun"]


def initial_reaction(core: DeploymentCore, scenario: Scenario, bounds: Bounds, control: ControlPort) -> None:
    """The scenario's initial facts, then the system's first reaction (no start fails)."""
    for ev in scenario.initial:
        core.observe(ev)
    act = bounds.start_action(scenario)
    if act is not None:
        core.step(ActionChange(act), control, force=True)
    else:
        log = run_sync(core.reaction(Stimulus(context_changed=True)), control)
        core.settle(e.graph for e in log.errors)


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


class RepositoryRun:
    """The deployment core on a fresh networkx repository, stepped event by event."""

    def __init__(self, scenario: Scenario, deployer: str | Deployer = "desmon", bounds: Bounds | None = None) -> None:
        self.scenario = scenario
        self.bounds = bounds or bounds_of(scenario)
        self.repo = Repository()
        load_model(self.repo, scenario.model)
        self.query = RepositoryQuery(self.repo)
        self.control = ScriptedControl(self.repo, scenario.model)
        self.core = DeploymentCore(scenario.model, self.query, RepositoryInsert(self.repo, scenario.model.robot), deployer)
        initial_reaction(self.core, scenario, self.bounds, self.control)

    def step(self, event: Event, fails: tuple[int, ...] = ()):  # type: ignore[no-untyped-def]
        """``event`` and the complete reaction; the ``fails``-th real starts of it fail."""
        self.control.arm(fails)
        return self.core.step(event, self.control)

    def key(self) -> Key:
        """The checker's key of the repository's current state (for cross-checks)."""
        failed = tuple(sorted(d["name"] for _n, d in self.repo.nodes(L.DEVICE) if not d["working"]))
        down = tuple(sorted(d["name"] for _n, d in self.repo.nodes(L.PLATFORM) if not d["up"]))
        loads = tuple((d["name"], tuple(sorted(d["load"].items()))) for _n, d in self.repo.nodes(L.PLATFORM) if d["load"])
        declared = {s.graph: s.requirements for s in self.scenario.model.specs}
        specs = tuple(sorted((s.graph, s.requirements) for s in self.core.specs() if s.requirements != declared[s.graph]))
        return Key(self.query.context(), failed, down, loads, self.query.deployments(), tuple(sorted(self.core.standing)), specs)

    def view(self) -> Any:
        """The SystemView of every invariant, ``history`` included (running list, stops, edges)."""
        history = sum(1 for _ in self.repo.edges(L.DEPLOYMENT_HISTORY))
        return self.core.view(running=tuple(sorted(self.control.running)), stops=self.control.stops, history=history)

    def violations(self, invariants=None):  # type: ignore[no-untyped-def]
        """The invariants on the current view, plus the last reaction's moves that broke
        ``no-flapping`` (its transition half, noted by the core)."""
        out = check_invariants(self.view(), invariants)
        if self.core.unjustified and (invariants is None or any(i.name == "no-flapping" for i in invariants)):
            if not any(name == "no-flapping" for name, _m in out):
                out.append(("no-flapping", self.core.unjustified[0]))
        return out
