"""A compact, state-backed Query + Insert + Control for the checker.

:class:`Key` is the frozen, hashable, canonical state: context, failed devices, platforms
down, background loads, active deployments and standing errors, every unordered part
sorted. :class:`StateStore` is loaded from a key, answers the QueryPort exactly as
:class:`~desmon.repository.query.RepositoryQuery` over the networkx repository would
(``tests/test_state_equivalence.py`` shows it with hypothesis), takes the context
monitor's Insert facts, and executes Control commands against an *outcome prefix*:
a start beyond the prefix succeeds and marks a choice point the checker may branch on.
"""

from __future__ import annotations

from typing import NamedTuple

from desmon.deployment.invariants import SystemView, check_invariants, Invariant
from desmon.errors import QueryError
from desmon.model.requirements import DeploymentSpec, Requirement
from desmon.model.system import PlatformState, SystemModel

__all__ = ["Key", "StateStore"]


class Key(NamedTuple):
    """The checker's state. Platforms and devices are named; every set is a sorted tuple."""

    context: str | None
    failed: tuple[str, ...]
    down: tuple[str, ...]
    loads: tuple[tuple[str, tuple[tuple[str, float], ...]], ...]  # (platform, sorted (resource, amount)) for set loads
    deployments: tuple[tuple[str, str], ...]  # sorted (graph, platform)
    standing: tuple[str, ...]


class StateStore:
    """QueryPort + InsertPort + ControlPort over a mutable copy of one :class:`Key`."""

    def __init__(self, model: SystemModel) -> None:
        self.model = model
        self.platform_names = tuple(p.name for p in model.platforms)
        self._platform = {p.name: p for p in model.platforms}
        self._device_platform = {d.name: d.platform for d in model.devices}
        self._devices_on = {p.name: tuple(d for d in model.devices if d.platform == p.name) for p in model.platforms}
        self._spec = {s.graph: s for s in model.specs}
        self._graphs = {g.name for g in model.graphs}
        self._use = {s.graph: s.consumption() for s in model.specs}
        self._ps_cache: dict[tuple, PlatformState] = {}
        # mutable state
        self.ctx: str | None = None
        self.failed: set[str] = set()
        self.down: set[str] = set()
        self.loads: dict[str, dict[str, float]] = {}
        self.deployed: set[tuple[str, str]] = set()
        self._states: tuple[PlatformState, ...] | None = None
        # control
        self.prefix: tuple[bool, ...] = ()
        self.outcomes: list[bool] = []
        self.watch: tuple[Invariant, ...] = ()
        self.watch_view: "object | None" = None  # callable () -> SystemView
        self.instant: tuple[str, str, str] | None = None  # (invariant, message, after command)

    # -- state --------------------------------------------------------------------------
    def load(self, key: Key) -> None:
        self.ctx = key.context
        self.failed = set(key.failed)
        self.down = set(key.down)
        self.loads = {p: dict(items) for p, items in key.loads}
        self.deployed = set(key.deployments)
        self._states = None

    def key(self, standing: frozenset[str] | tuple[str, ...] = ()) -> Key:
        return Key(
            self.ctx,
            tuple(sorted(self.failed)),
            tuple(sorted(self.down)),
            tuple((p, tuple(sorted(self.loads[p].items()))) for p in self.platform_names if p in self.loads),
            tuple(sorted(self.deployed)),
            tuple(sorted(standing)),
        )

    def begin(self, prefix: tuple[bool, ...] = ()) -> None:
        """Start executing a reaction: starts follow ``prefix``, then succeed."""
        self.prefix = prefix
        self.outcomes = []
        self.instant = None

    # -- QueryPort ----------------------------------------------------------------------
    def deployment_information(self, graph: str) -> DeploymentSpec | None:
        return self._spec.get(graph) if graph in self._graphs else None

    def fixed_platform(self, spec: DeploymentSpec) -> str | None:
        s = self._spec.get(spec.graph)
        return s.fixed_platform if s is not None else None

    def constraints(self, spec: DeploymentSpec) -> tuple[Requirement, ...]:
        s = self._spec.get(spec.graph)
        return s.requirements if s is not None else ()

    def platform_state(self, platform: str) -> PlatformState:
        if platform not in self._platform:
            raise QueryError(f"unknown platform {platform!r}")
        failed = self.failed
        devices = tuple(d for d in self._devices_on[platform] if d.name not in failed)
        load = tuple(sorted(self.loads[platform].items())) if platform in self.loads else ()
        deployed = tuple(sorted((g, self._use.get(g, ())) for g, p in self.deployed if p == platform))
        up = platform not in self.down
        ck = (platform, up, devices, load, deployed)
        st = self._ps_cache.get(ck)
        if st is None:
            st = PlatformState(self._platform[platform], up, devices, load, deployed)
            self._ps_cache[ck] = st
        return st

    def platform_states(self) -> tuple[PlatformState, ...]:
        if self._states is None:
            self._states = tuple(self.platform_state(p) for p in self.platform_names)
        return self._states

    def deployed_on(self, graph: str) -> tuple[str, ...]:
        if graph not in self._spec:
            return ()
        return tuple(sorted(p for g, p in self.deployed if g == graph))

    def active_deployments(self, platform: str) -> tuple[str, ...]:
        if platform not in self._platform:
            raise QueryError(f"unknown platform {platform!r}")
        return tuple(sorted(g for g, p in self.deployed if p == platform))

    def perception_graph(self, deployment: str) -> str:
        if deployment not in self._spec:
            raise QueryError(f"unknown deployment {deployment!r}")
        return deployment

    def context(self) -> str | None:
        return self.ctx

    def deployments(self) -> tuple[tuple[str, str], ...]:
        return tuple(sorted(self.deployed))

    # -- InsertPort ---------------------------------------------------------------------
    def set_context(self, context: str) -> bool:
        if self.ctx == context:
            return False
        self.ctx = context
        return True

    def set_device_working(self, device: str, working: bool) -> str | None:
        if device not in self._device_platform:
            raise QueryError(f"unknown device {device!r}: it is not in the repository")
        if (device not in self.failed) == working:
            return None
        if working:
            self.failed.discard(device)
        else:
            self.failed.add(device)
        self._states = None
        return self._device_platform[device]

    def set_platform_up(self, platform: str, up: bool) -> bool:
        if platform not in self._platform:
            raise QueryError(f"unknown platform {platform!r}: it is not in the repository")
        if (platform not in self.down) == up:
            return False
        if up:
            self.down.discard(platform)
        else:
            self.down.add(platform)
        self._states = None
        return True

    def set_load(self, platform: str, resource: str, amount: float) -> bool:
        if platform not in self._platform:
            raise QueryError(f"unknown platform {platform!r}: it is not in the repository")
        cur = self.loads.get(platform, {})
        if cur.get(resource, 0.0) == amount:
            return False
        cur = dict(cur)
        cur[resource] = amount
        self.loads[platform] = cur
        self._states = None
        return True

    # -- ControlPort (ImmediateControl semantics, starts follow the outcome prefix) --------
    def start(self, graph: str, platform: str) -> bool:
        if (graph, platform) in self.deployed:
            return True
        i = len(self.outcomes)
        ok = self.prefix[i] if i < len(self.prefix) else True
        self.outcomes.append(ok)
        if ok:
            self.deployed.add((graph, platform))
            self._states = None
            self._watch(f"start {graph} on {platform}")
        return ok

    def stop(self, graph: str, platform: str) -> bool:
        if (graph, platform) not in self.deployed:
            return False
        self.deployed.discard((graph, platform))
        self._states = None
        self._watch(f"stop {graph} on {platform}")
        return True

    def _watch(self, after: str) -> None:
        if not self.watch or self.instant is not None or self.watch_view is None:
            return
        bad = check_invariants(self.watch_view(), self.watch)  # type: ignore[operator]
        if bad:
            self.instant = (bad[0][0], bad[0][1], after)


def view_from(store: StateStore, standing: frozenset[str], slots: tuple[tuple[str, ...], ...]) -> SystemView:
    return SystemView(store.platform_states(), store.model.specs, standing, slots)
