"""A hypothesis ``RuleBasedStateMachine`` over the networkx repository.

Its rules are the checker's events (action change, device fail/repair, platform
down/up, load step, each with optional start failures, as the initial reaction), its invariants the named
invariants of docs/design.md §9 (the instantaneous ones also after every start
inside a reaction, as the checker watches them) -- including ``history``, which here sees the
infrastructure's running list, its stop count and the DEPLOYMENT_HISTORY edges. It
drives the same :class:`~desmon.deployment.core.DeploymentCore` as the checker.

``make_machine(scenario, deployer)`` returns the class; ``TestCase`` runs it in pytest.
:class:`RepositoryRun` and :class:`ScriptedControl` live in :mod:`desmon.verify.replay`
(re-exported here).
"""

from __future__ import annotations

from typing import Callable

from hypothesis import strategies as st
from hypothesis.stateful import RuleBasedStateMachine, initialize, invariant, rule

from desmon.deployment.deployer import Deployer
from desmon.model.events import DeviceEvent, Event, PlatformEvent
from desmon.model.scenario import Scenario
from desmon.verify.bounds import Bounds, bounds_of
from desmon.verify.replay import RepositoryRun, ScriptedControl
from desmon.verify.strategies import LAST_START, reach, start_failures

__all__ = ["ScriptedControl", "RepositoryRun", "make_machine"]


def make_machine(scenario: Scenario, deployer: str | Deployer = "desmon", bounds: Bounds | None = None) -> type[RuleBasedStateMachine]:
    """A state machine class exploring ``scenario``'s bounded events on the networkx repository."""
    b = bounds or bounds_of(scenario)
    from desmon.verify.checker import Checker

    enabler = Checker(scenario, deployer, bounds=b)  # only its enabled() is used: the bounds' event rules
    _events, last_start = reach(scenario, b)
    failing = start_failures(b, max_index=max(LAST_START, last_start))
    watched = {i.name for i in enabler.system.instant}

    class DeploymentMachine(RuleBasedStateMachine):
        @initialize(initial=failing)
        def start(self, initial: tuple[int, ...]) -> None:
            self.run = RepositoryRun(scenario, deployer, b, initial_fails=initial, unissued_fails_drop=True)
            self.trace: list[tuple[Event, tuple[int, ...]]] = []
            first = [f for f in self.run.initial_found if f[0] in watched]
            assert not first, (
                f"{first[0][0]}: {first[0][1]} during the initial reaction (failing starts {list(self.run.initial_fails)}), right after `{first[0][2]}`"
            )

        def _do(self, data, family: Callable[[Event], bool]) -> None:  # type: ignore[no-untyped-def]
            options = [e for e in enabler.enabled(self.run.key()) if family(e)]
            if not options:
                return
            event = data.draw(st.sampled_from(options), label="event")
            fails = data.draw(failing, label="failing starts")
            self.trace.append((event, fails))
            _result, during = self.run.step_watching(event, fails, enabler.system.instant)
            assert during is None, (  # an instantaneous invariant, broken inside the reaction (maybe repaired by its end)
                f"{during[0]}: {during[1]} during the reaction, right after `{during[2]}`, after {[str(e) for e, _ in self.trace]}"
            )

        @rule(data=st.data())
        def action(self, data) -> None:  # type: ignore[no-untyped-def]
            self._do(data, lambda e: e.role == "action")

        @rule(data=st.data())
        def device(self, data) -> None:  # type: ignore[no-untyped-def]
            self._do(data, lambda e: isinstance(e, DeviceEvent))

        @rule(data=st.data())
        def platform(self, data) -> None:  # type: ignore[no-untyped-def]
            self._do(data, lambda e: isinstance(e, PlatformEvent) and e.role == "fault")

        @rule(data=st.data())
        def load(self, data) -> None:  # type: ignore[no-untyped-def]
            self._do(data, lambda e: e.role == "load")

        @rule(data=st.data())
        def runtime_change(self, data) -> None:  # type: ignore[no-untyped-def]
            self._do(data, lambda e: e.role == "change")

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
