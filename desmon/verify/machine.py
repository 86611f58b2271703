"""A hypothesis ``RuleBasedStateMachine`` over the networkx repository.

Its rules are the checker's events (action change, device fail/repair, platform
down/up, load step, each with optional start failures), its invariants the named
invariants of DESIGN.md §5 -- including ``history``, which here sees the
infrastructure's running list, its stop count and the DEPLOYMENT_HISTORY edges. It
drives the same :class:`~desmon.deployment.core.DeploymentCore` as the checker.

``make_machine(scenario, deployer)`` returns the class; ``TestCase`` runs it in pytest.
"""

from __future__ import annotations

from hypothesis import strategies as st
from hypothesis.stateful import RuleBasedStateMachine, initialize, invariant, rule

from desmon.deployment.core import DeploymentCore, run_sync
from desmon.deployment.deployer import Deployer
from desmon.deployment.invariants import check_invariants
from desmon.deployment.monitor import Stimulus
from desmon.model.events import ActionChange, Event
from desmon.model.scenario import Scenario
from desmon.repository import labels as L
from desmon.repository.facts import ImmediateControl, RepositoryInsert, load_model
from desmon.repository.query import RepositoryQuery
from desmon.repository.store import Repository
from desmon.verify.bounds import Bounds, bounds_of
from desmon.verify.state import Key
from desmon.verify.strategies import start_failures

__all__ = ["ScriptedControl", "RepositoryRun", "make_machine"]


class ScriptedControl(ImmediateControl):
    """ImmediateControl whose real starts (not the no-op restarts) fail at given indices."""

    def __init__(self, repo: Repository) -> None:
        super().__init__(repo)
        self.fail_at: tuple[int, ...] = ()
        self.n = 0

    def arm(self, fails: tuple[int, ...]) -> None:
        self.fail_at, self.n = fails, 0

    def start(self, graph: str, platform: str) -> bool:
        if (graph, platform) in self.running:
            return True
        i, self.n = self.n, self.n + 1
        if i in self.fail_at:
            return False
        return super().start(graph, platform)


class RepositoryRun:
    """The deployment core on a fresh networkx repository, stepped event by event."""

    def __init__(self, scenario: Scenario, deployer: str | Deployer = "desmon", bounds: Bounds | None = None) -> None:
        self.scenario = scenario
        self.bounds = bounds or bounds_of(scenario)
        self.repo = Repository()
        load_model(self.repo, scenario.model)
        self.query = RepositoryQuery(self.repo)
        self.control = ScriptedControl(self.repo)
        self.core = DeploymentCore(scenario.model, self.query, RepositoryInsert(self.repo, scenario.model.robot), deployer)
        for ev in scenario.initial:
            self.core.observe(ev)
        act = self.bounds.start_action(scenario)
        if act is not None:
            self.core.step(ActionChange(act), self.control, force=True)
        else:
            log = run_sync(self.core.reaction(Stimulus(context_changed=True)), self.control)
            self.core.settle(e.graph for e in log.errors)

    def step(self, event: Event, fails: tuple[int, ...] = ()):  # type: ignore[no-untyped-def]
        self.control.arm(fails)
        return self.core.step(event, self.control)

    def key(self) -> Key:
        """The checker's key of the repository's current state (for cross-checks)."""
        g = self.repo.graph
        failed = tuple(sorted(d for nid, d_ in self.repo.nodes(L.DEVICE) for d in [d_["name"]] if not d_["working"]))
        down = tuple(sorted(d["name"] for _n, d in self.repo.nodes(L.PLATFORM) if not d["up"]))
        loads = tuple((d["name"], tuple(sorted(d["load"].items()))) for _n, d in self.repo.nodes(L.PLATFORM) if d["load"])
        del g
        return Key(self.query.context(), failed, down, loads, self.query.deployments(), tuple(sorted(self.core.standing)))

    def violations(self, invariants=None):  # type: ignore[no-untyped-def]
        history = sum(1 for _ in self.repo.edges(L.DEPLOYMENT_HISTORY))
        view = self.core.view(running=tuple(sorted(self.control.running)), stops=self.control.stops, history=history)
        return check_invariants(view, invariants)


def make_machine(scenario: Scenario, deployer: str | Deployer = "desmon", bounds: Bounds | None = None) -> type[RuleBasedStateMachine]:
    """A state machine class exploring ``scenario``'s bounded events on the networkx repository."""
    b = bounds or bounds_of(scenario)
    from desmon.verify.checker import Checker

    enabler = Checker(scenario, deployer, bounds=b)  # only its enabled() is used: the bounds' event rules

    class DeploymentMachine(RuleBasedStateMachine):
        @initialize()
        def start(self) -> None:
            self.run = RepositoryRun(scenario, deployer, b)
            self.trace: list[tuple[Event, tuple[int, ...]]] = []

        def _do(self, data, kinds: tuple[type, ...]) -> None:  # type: ignore[no-untyped-def]
            options = [e for e in enabler.enabled(self.run.key()) if isinstance(e, kinds)]
            if not options:
                return
            event = data.draw(st.sampled_from(options), label="event")
            fails = data.draw(start_failures(b), label="failing starts")
            self.trace.append((event, fails))
            self.run.step(event, fails)

        @rule(data=st.data())
        def action(self, data) -> None:  # type: ignore[no-untyped-def]
            from desmon.model.events import ActionChange as A

            self._do(data, (A,))

        @rule(data=st.data())
        def device(self, data) -> None:  # type: ignore[no-untyped-def]
            from desmon.model.events import DeviceFail, DeviceRepair

            self._do(data, (DeviceFail, DeviceRepair))

        @rule(data=st.data())
        def platform(self, data) -> None:  # type: ignore[no-untyped-def]
            from desmon.model.events import PlatformDown, PlatformUp

            self._do(data, (PlatformDown, PlatformUp))

        @rule(data=st.data())
        def load(self, data) -> None:  # type: ignore[no-untyped-def]
            from desmon.model.events import LoadChange

            self._do(data, (LoadChange,))

    def _make_inv(name: str):  # type: ignore[no-untyped-def]
        from desmon.deployment.invariants import INVARIANTS

        inv = INVARIANTS[name]

        def check(self) -> None:  # type: ignore[no-untyped-def]
            bad = self.run.violations((inv,))
            assert not bad, f"{name}: {bad[0][1]} after {[str(e) for e, _ in self.trace]}"

        check.__name__ = "inv_" + name.replace("-", "_")
        return invariant()(check)

    from desmon.deployment.invariants import INVARIANTS

    for n in INVARIANTS:
        f = _make_inv(n)
        setattr(DeploymentMachine, f.__name__, f)
    DeploymentMachine.__name__ = f"DeploymentMachine_{scenario.name}"
    return DeploymentMachine
