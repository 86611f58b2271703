"""The Control semantics: when the infrastructure refuses a start or a stop.

Written once and used by every engine (``docs/design.md`` §6; the rules, and the test that holds every engine to them: ``docs/findings.md``, "One Control semantics"):

* the scripted replay and the checker's repository replay
  (:func:`repository_control`),
* the checker's state store (:class:`desmon.verify.state.StateStore`),
* the SimPy infrastructure (``desmon.sim.infrastructure.Infrastructure.start``), on the
  *physical* facts at the moment the start completes.

Rules
    A start of a graph on a platform it already runs on is a no-op success. Otherwise
    the start is **refused** when

    1. the platform is down, or
    2. the platform's working devices no longer meet the device requirements of the
       graph's deployment specification (Quantity, ``Attribute(platform_has, kind)``, and
       Selections whose options are all devices), or
    3. one of the device kinds the graph's sensor components read has no readable
       device: the graph reads the platform's own devices of that kind if it has any,
       else every device of that kind on the robot; a device is readable while it works
       and its platform is up. (A kind no device of the model provides at all -- a
       model without devices, for pure platform studies -- imposes no rule.)

    A start that is not refused may still fail by the environment's failure model (the
    checker's bounded ``start_failures`` choice points, the world's scripted or random
    start failures). A stop succeeds exactly when the graph runs on the platform, down
    or not (the infrastructure can always drop an instance it knows of).

Both rules are evaluated with :func:`~desmon.deployment.validity.check_platform`, so
the checker's table engine observes them like any requirement check.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Callable

from desmon.deployment.validity import check_platform, input_failures
from desmon.repository.facts import ImmediateControl
from desmon.repository.query import RepositoryQuery
from desmon.repository.store import Repository
from desmon.model.platform import Device
from desmon.model.requirements import DeploymentSpec, Reads, Requirement
from desmon.model.system import PlatformState, SystemModel

if TYPE_CHECKING:
    from desmon.deployment.ports import ChecksPort

__all__ = ["ControlRules", "repository_control", "repository_refusal", "StateOf", "PLATFORM_DOWN", "device_requirements"]

#: ``platform name -> its PlatformState`` (the facts the rules read).
StateOf = Callable[[str], PlatformState]

#: The refusal reason of rule 1.
PLATFORM_DOWN = "platform down"


def device_requirements(requirements: tuple[Requirement, ...]) -> tuple[Requirement, ...]:
    """The requirements among ``requirements`` that only a platform's devices decide (each
    kind says: :meth:`~desmon.model.kinds.Constraint.device_only`)."""
    return tuple(r for r in requirements if r.device_only())


class ControlRules:
    """The start rules for one model (its input wiring memoised per graph and platform)."""

    __slots__ = ("model", "spec_of", "checks", "_wiring", "_device_reqs")

    def __init__(
        self, model: SystemModel, spec_of: "Callable[[str], DeploymentSpec | None] | None" = None, checks: "ChecksPort | None" = None
    ) -> None:
        self.model = model
        #: the Checks port the rules ask (None: the default memoised checks)
        self.checks = checks
        #: the current specification of a graph (requirements may change at run time);
        #: None reads the model's declared ones
        self.spec_of = spec_of
        self._wiring: dict[tuple[str, str], tuple[tuple[str, tuple[Device, ...]], ...]] = {}
        self._device_reqs: dict[int, tuple[tuple, tuple[Requirement, ...]]] = {}

    def input_devices(self, graph: str, platform: str) -> tuple[tuple[str, tuple[Device, ...]], ...]:
        """``(kind, devices)`` per device kind ``graph`` reads when it runs on ``platform``:
        the platform's own devices of that kind if it has any, else every device of that
        kind (in declaration order); a kind no device provides is left out, as rule 3
        leaves it (a pure platform study: nothing to read, so no input to lose). The SimPy
        world wires a detector's inputs this way, and desmon analyze its chain's."""
        key = (graph, platform)
        found = self._wiring.get(key)
        if found is None:
            model = self.model
            out = []
            for kind in model.graph(graph).device_kinds:
                readable = model.readable(graph, kind)  # (a fleet's merged model: its own robot's)
                devices = tuple(d for d in readable if d.platform == platform) or readable
                if devices:
                    out.append((kind, devices))
            found = self._wiring[key] = tuple(out)
        return found

    def _declared_reads(self, graph: str) -> tuple[Reads, ...]:
        spec = self.model.spec(graph)
        return spec.reads if spec is not None else ()

    def _device_reqs_of(self, declared: tuple[Requirement, ...]) -> tuple[Requirement, ...]:
        """:func:`device_requirements` of ``declared``, kept per tuple and found by its
        identity (no requirement's Python-level hash); the entry holds the tuple its key names."""
        found = self._device_reqs.get(id(declared))
        if found is not None and found[0] is declared:
            return found[1]
        if len(self._device_reqs) > 4096:
            self._device_reqs.clear()
        reqs = device_requirements(declared)
        self._device_reqs[id(declared)] = (declared, reqs)
        return reqs

    def start_refusal(self, graph: str, platform: str, state_of: StateOf) -> str | None:
        """Why the infrastructure refuses to start ``graph`` on ``platform``, or None.

        ``state_of`` gives a platform's current facts (only ``up`` and the working
        devices are read, through :func:`check_platform`).
        """
        checks = self.checks
        if check_platform((), state_of(platform), graph, checks=checks):
            return PLATFORM_DOWN
        spec = self.spec_of(graph) if self.spec_of is not None else self.model.spec(graph)
        reqs = self._device_reqs_of(spec.requirements if spec is not None else ())
        if reqs and check_platform(reqs, state_of(platform), graph, first_only=True, checks=checks):
            return f"the devices of {platform} no longer meet {', '.join(r.describe() for r in reqs)}"
        reads = spec.reads if spec is not None else self._declared_reads(graph)
        if reads:
            st = state_of(platform)
            own = tuple(r for r in reads if platform in r.hosts)  # its own half (rule 3 on its devices)
            fails = check_platform(own, st, graph, first_only=True, checks=checks) if own else ()
            if not fails:
                fails = input_failures(reads, platform, state_of, graph, checks=checks)
            if fails:
                return f"{fails[0].requirement}: {fails[0].reason}"
        return None


def repository_refusal(repo: Repository, model: SystemModel) -> Callable[[str, str], str | None]:
    """``refuse(graph, platform)`` of the Control rules, reading the facts from ``repo``."""
    query = RepositoryQuery(repo)
    rules = ControlRules(model, query.deployment_information)
    state_of = query.platform_state
    return lambda graph, platform: rules.start_refusal(graph, platform, state_of)


def repository_control(
    repo: Repository, model: SystemModel, fails: Callable[[str, str], bool] | None = None
) -> ImmediateControl:
    """An instant Control port on a networkx repository that follows the Control rules;
    ``fails`` as in :class:`ImmediateControl`."""
    return ImmediateControl(repo, fails, repository_refusal(repo, model))
