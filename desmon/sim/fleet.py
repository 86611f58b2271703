"""A fleet in the SimPy world: many robots sharing edge servers, in one environment.

One :class:`Fleet` (the ``world`` of a fleet scenario) lists its robots -- each a
:class:`~desmon.model.scenario.Scenario` of its own (model, initial facts, World) whose
platforms, devices and graphs carry the robot's prefix (``r017.arm_pc``) -- and the
names of the edge servers every robot's model declares (the same Platform in each).

:class:`FleetWorld` runs them in one SimPy environment over one shared networkx
:class:`~desmon.repository.store.Repository`: every robot's platforms, devices, graphs
and requirements, the shared edge servers and one Robot node per robot. Each robot is
assembled from the same parts as a :class:`~desmon.sim.engine.SimWorld`
(:mod:`desmon.sim.parts`: robot, context monitor, deployer, faults, loads) and its
deployment core reads the repository through its own :class:`RobotView`: its own context, its own PCs and the edge servers -- never another
robot's PCs -- and only its own deployments to stop or re-check. An edge server's
``deployed`` facts hold every robot's detectors, so one robot's deployment there takes
capacity every other robot's deployer sees (and the ``no-overcommit`` audit checks).

Signals are off in a fleet: exposure counts a running, warmed-up valid detector as
monitoring (as ``World(signals=False)`` does) and slips are injected, not detected.
Edge servers never fail and are never leased (they are always there).

One subscription routes the repository's changes to the robots they concern (a
robot's context to that robot, a platform change to its owner or, for an edge server,
to every robot); platform states are cached and re-read only when a change marks them,
so no event copies the repository.
"""

from __future__ import annotations

import math
import random
import resource
import sys
import time
from dataclasses import dataclass, field
from typing import IO, Any, Callable, Iterable, Sequence

import simpy

from desmon.deployment.exposure import CAUSES
from desmon.deployment.invariants import SystemView
from desmon.errors import QueryError, ScenarioError
from desmon.model.checks import check_items, check_names, strict_init
from desmon.model.platform import Platform
from desmon.model.scenario import Scenario
from desmon.deployment.memo import MemoChecks
from desmon.deployment.placement import PlatformMemoColumnChecks
from desmon.deployment.validity import check_platform, reads_fixed_facts
from desmon.model.requirements import Capacity, DeploymentSpec, Requirement, fits
from desmon.model.system import PlatformState, Rule, RuleTable, SystemModel
from desmon.repository import labels as L
from desmon.repository.facts import load_model
from desmon.repository.query import RepositoryQuery
from desmon.repository.store import ADD_EDGE, UPDATE_NODE, Change, Repository, node_id
from desmon.sim.accounting import audit, robot_metrics
from desmon.sim.collector import collector_relaxed
from desmon.sim.parts import RobotParts, robot_parts, start_processes
from desmon.sim.processes import apply_initial
from desmon.sim.trace import Trace
from desmon.sim.world import World

__all__ = [
    "Fleet", "FleetWorld", "FleetResult", "RobotView", "simulate_fleet", "merged_model",
    "is_fleet", "robot_seed", "peak_rss_mb",
]


@strict_init(ScenarioError)
@dataclass(frozen=True, slots=True)
class Fleet:
    """A fleet: ``robots`` (one Scenario each, with a World) sharing the ``edges``.

    Every robot's model declares the edge servers (the same Platform objects); every
    other platform, device and graph name belongs to exactly one robot. All robots
    share one horizon. Signals must be off and no robot leases on-demand platforms.
    """

    robots: tuple[Scenario, ...]
    edges: tuple[str, ...] = ()
    description: str = ""
    #: an edge server admits a start only if the detector still fits when the start
    #: completes (its own capacity check); without it two robots that decide at the same
    #: time can over-commit it (each start is in flight, invisible to the other deployer)
    admission: bool = True

    def __post_init__(self) -> None:
        robots = check_items("fleet: robots", self.robots, Scenario, error=ScenarioError, example="robots=(Scenario(...), ...)")
        if not robots:
            raise ScenarioError("fleet: robots is empty: give at least one robot Scenario")
        object.__setattr__(self, "robots", robots)
        edges = check_names("fleet: edges", self.edges, each="edge server", error=ScenarioError, example="('edge00', 'edge01')")
        twice = [e for i, e in enumerate(edges) if e in edges[:i]]
        if twice:
            raise ScenarioError(f"fleet: edges name {twice[0]!r} twice: give each edge server once")
        object.__setattr__(self, "edges", edges)
        if not isinstance(self.description, str):
            raise ScenarioError(f"fleet: description {self.description!r} is not text: give a string")
        if not isinstance(self.admission, bool):
            raise ScenarioError(f"fleet: admission = {self.admission!r} is not True or False: give a bool")
        self._check_robots()

    def _check_robots(self) -> None:
        shared = self._shared_platforms()
        first = self.robots[0]
        owner: dict[str, str] = {}
        robots: set[str] = set()
        for sc in self.robots:
            name = sc.model.robot
            if name in robots:
                raise ScenarioError(f"fleet: two robots are named {name!r}: give each robot model its own robot= name")
            robots.add(name)
            _check_robot_world(sc, first)
            for e, plat in shared.items():
                mine = next((p for p in sc.model.platforms if p.name == e), None)
                if mine != plat:
                    why = "does not declare" if mine is None else "declares otherwise than the first robot"
                    raise ScenarioError(f"fleet: robot {name!r} {why} edge server {e!r}: every robot declares the same edge servers")
            _claim_names(sc.model, shared, owner)
        _check_edge_masters(self.robots, set(self.edges))

    def _shared_platforms(self) -> dict[str, Platform]:
        """The edge servers as the first robot declares them (always there, not on demand)."""
        first = self.robots[0].model
        shared: dict[str, Platform] = {}
        for e in self.edges:
            plat = next((p for p in first.platforms if p.name == e), None)
            if plat is None:
                raise ScenarioError(
                    f"fleet: edge server {e!r} is not a platform of robot {first.robot!r}: declare it in every robot's model"
                )
            if plat.on_demand:
                raise ScenarioError(f"fleet: edge server {e!r} is on demand: a fleet's edge servers are always there; drop on_demand")
            shared[e] = plat
        return shared

    @property
    def horizon(self) -> float:
        return float(self.robots[0].world.horizon)

    def check_against(self, scenario: Scenario) -> None:
        """As a Scenario's ``world``: the scenario's model declares every edge server."""
        names = {p.name for p in scenario.model.platforms}
        missing = [e for e in self.edges if e not in names]
        if missing:
            raise ScenarioError(f"fleet: edge server {missing[0]!r} is not a platform of scenario {scenario.name!r}'s model")


def _check_robot_world(sc: Scenario, first: Scenario) -> None:
    """A robot of a fleet has a World with signals off, no lease, the first robot's horizon."""
    name = sc.model.robot
    if not isinstance(sc.world, World):
        raise ScenarioError(f"fleet: robot {name!r} has no World: give its Scenario world=World(...)")
    if sc.world.signals:
        raise ScenarioError(f"fleet: robot {name!r} simulates signals: a fleet runs with World(signals=False)")
    if sc.world.lease is not None:
        raise ScenarioError(f"fleet: robot {name!r} leases platforms: a fleet shares fixed edge servers; drop World(lease=...)")
    horizon = first.world.horizon if isinstance(first.world, World) else sc.world.horizon
    if sc.world.horizon != horizon:
        raise ScenarioError(
            f"fleet: robot {name!r} has horizon {sc.world.horizon:g} s, robot {first.model.robot!r} {horizon:g} s: "
            "give every robot the same horizon"
        )


def _claim_names(model: SystemModel, shared: dict[str, Platform], owner: dict[str, str]) -> None:
    """Record ``model``'s platform (edge servers aside), device and graph names as its
    robot's; a name another robot already owns is refused."""
    name = model.robot
    for what, names in (
        ("platform", [p.name for p in model.platforms if p.name not in shared]),
        ("device", [d.name for d in model.devices]),
        ("graph", [g.name for g in model.graphs]),
    ):
        for n in names:
            key = f"{what}:{n}"
            if key in owner:
                raise ScenarioError(
                    f"fleet: {what} {n!r} belongs to robots {owner[key]!r} and {name!r}: prefix each robot's names (e.g. '{name}.{n}')"
                )
            owner[key] = name


def is_fleet(scenario: Scenario) -> bool:
    """Is ``scenario`` a fleet scenario (its world a :class:`Fleet`)?"""
    return isinstance(scenario.world, Fleet)


def merged_model(robots: Iterable[SystemModel], edges: Iterable[str], robot: str = "fleet") -> SystemModel:
    """One SystemModel of several robot models that share ``edges`` and ONE context:
    every platform (each edge once), device, graph and specification, and per context
    the slots of every robot. What the checker verifies for a small fleet."""
    models = list(robots)
    edge_set = set(edges)
    platforms: list[Platform] = []
    seen: set[str] = set()
    slots: dict[str, list[tuple[str, ...]]] = {}
    for m in models:
        for p in m.platforms:
            if p.name in edge_set and p.name in seen:
                continue
            seen.add(p.name)
            platforms.append(p)
        for r in m.rules.rules:
            slots.setdefault(r.context, []).extend(r.slots)
    return SystemModel(
        platforms=tuple(platforms),
        devices=tuple(d for m in models for d in m.devices),
        graphs=tuple(g for m in models for g in m.graphs),
        specs=tuple(s for m in models for s in m.specs),
        rules=RuleTable(tuple(Rule(c, tuple(s)) for c, s in slots.items())),
        robot=robot,
        declared_actions=models[0].declared_actions if models else (),
        # each robot's graphs read its own devices only, as in the fleet run
        owners=tuple((x.name, m.robot) for m in models for x in (*m.graphs, *m.devices)),
    )


class _StateCache:
    """Platform states of the shared repository, re-read only when a change marks them."""

    def __init__(self, repo: Repository) -> None:
        self.query = RepositoryQuery(repo)
        self.states: dict[str, PlatformState] = {}
        self.watchers: dict[str, list[RobotView]] = {}
        self.reads = 0

    def watch(self, view: "RobotView", platforms: Iterable[str]) -> None:
        for p in platforms:
            self.watchers.setdefault(p, []).append(view)

    def mark(self, platform: str) -> None:
        self.states.pop(platform, None)
        for view in self.watchers.get(platform, ()):
            view.stale(platform)

    def mark_all(self) -> None:
        self.states.clear()
        for platform, views in self.watchers.items():
            for view in views:
                view.stale(platform)

    def state(self, platform: str) -> PlatformState:
        s = self.states.get(platform)
        if s is None:
            s = self.states[platform] = self.query.platform_state(platform)
            self.reads += 1
        return s


class RobotView(RepositoryQuery):
    """One robot's Query port on the shared repository.

    Its context is its own Robot node's; its platforms are its own PCs and the edge
    servers one of its graphs may use by their fixed facts (in that order; see
    :meth:`_select`); the deployments it lists, stops or re-checks are its own graphs'.
    A platform's ``deployed`` facts are everyone's: capacity is shared. Another robot's
    PC is not its to ask about (:class:`~desmon.errors.QueryError`).
    ``platform_states`` hands out the same tuple while none of its platforms changed and
    re-reads only the ones that did.
    """

    def __init__(
        self, repo: Repository, robot: str, own: tuple[str, ...], edges: tuple[str, ...], graphs: tuple[str, ...], cache: _StateCache,
        checks: Any = None,
    ) -> None:
        super().__init__(repo, checks)
        self.validity_memo = None  # a fleet's facts seldom recur: no memo to hold old states alive
        self.robot = robot
        self.own = own
        self.edges = edges
        self.graph_names = graphs
        self._own_graphs = frozenset(graphs)
        self._own_platforms = frozenset(own + edges)
        self._robot_id = node_id(L.ROBOT, robot)
        self._context_key = (self._robot_id, L.IN_CONTEXT)
        self._context: tuple[int | None, str | None] = (-1, None)  # (the stamp it was read at, the context)
        self._cache = cache
        self._deployed: dict[str, tuple[str, ...]] = {}  # graph -> platforms, until a DEPLOYED_ON change
        self._deployments: tuple[tuple[str, str], ...] | None = None
        self._specs: dict[str, DeploymentSpec | None] = {}  # graph -> spec, for one specs_version
        self._specs_at = -1
        self._usable_at = -1
        self.platform_names: tuple[str, ...] = ()
        self._select()
        cache.watch(self, own + edges)

    def _select(self) -> None:
        """The platforms in the view: its own PCs, and the edge servers that one of its
        graphs may use by their fixed facts (properties, attributes: a link too slow for
        every detector rules a server out for good, until a requirement changes)."""
        self._usable_at = self.repo.specs_version
        reqs = [
            tuple(r for r in spec.requirements if reads_fixed_facts(r))
            for spec in (self.deployment_information(g) for g in self.graph_names)
            if spec is not None and spec.fixed_platform is None
        ]
        fixed = {spec.fixed_platform for spec in (self.deployment_information(g) for g in self.graph_names) if spec is not None}
        usable = tuple(
            e for e in self.edges
            if e in fixed or any(not check_platform(r, PlatformState(self._cache.state(e).platform), None, checks=self.checks) for r in reqs)
        )
        self.platform_names = self.own + usable
        self._index = {p: i for i, p in enumerate(self.platform_names)}
        self._rows: list[PlatformState] = []  # filled on first use
        self._dirty: set[int] = set()
        self._states: tuple[PlatformState, ...] | None = None  # None: one of its platforms changed

    def context(self) -> str | None:
        """Its Robot node's context; re-read only after an IN_CONTEXT edge of that node
        changed (a context node's name is fixed when it is added)."""
        stamp = self.repo.edge_touched.get(self._context_key)
        memo = self._context
        if memo[0] == stamp:
            return memo[1]
        ctx = self.repo.successors(self._robot_id, L.IN_CONTEXT)
        name = str(self.repo.node_data[ctx[0]]["name"]) if ctx else None
        self._context = (stamp, name)
        return name

    def platform_state(self, platform: str) -> PlatformState:
        if platform not in self._own_platforms:
            raise QueryError(f"robot {self.robot!r} cannot use platform {platform!r}: it is another robot's")
        return self._cache.state(platform)

    def platform_states(self) -> tuple[PlatformState, ...]:
        if self._usable_at != self.repo.specs_version:
            self._select()
        states = self._states
        if states is None:
            state = self._cache.state
            rows = self._rows
            if not rows:
                rows.extend(state(p) for p in self.platform_names)
            for i in self._dirty:
                rows[i] = state(self.platform_names[i])
            self._dirty.clear()
            states = self._states = tuple(rows)
        return states

    def stale(self, platform: str) -> None:
        """``platform`` changed: re-read its state on the next call (the others are kept)."""
        i = self._index.get(platform)
        if i is not None:
            self._states = None
            self._dirty.add(i)

    def forget_deployments(self, graph: str | None = None) -> None:
        """A DEPLOYED_ON edge of ``graph`` (None: of any of this robot's graphs) changed."""
        if graph is None:
            self._deployed.clear()
        else:
            self._deployed.pop(graph, None)
        self._deployments = None

    def deployed_on(self, graph: str) -> tuple[str, ...]:
        on = self._deployed.get(graph)
        if on is None:
            on = self._deployed[graph] = super().deployed_on(graph)
        return on

    def deployment_information(self, graph: str) -> DeploymentSpec | None:
        if self._specs_at != self.repo.specs_version:
            self._specs.clear()
            self._specs_at = self.repo.specs_version
        if graph not in self._specs:
            self._specs[graph] = super().deployment_information(graph)
        return self._specs[graph]

    def constraints(self, spec: DeploymentSpec) -> tuple[Requirement, ...]:
        current = self.deployment_information(spec.graph)
        return current.requirements if current is not None else super().constraints(spec)

    def fixed_platform(self, spec: DeploymentSpec) -> str | None:
        current = self.deployment_information(spec.graph)
        return current.fixed_platform if current is not None else super().fixed_platform(spec)

    def active_deployments(self, platform: str) -> tuple[str, ...]:
        return tuple(g for g in super().active_deployments(platform) if g in self._own_graphs)

    def deployments(self) -> tuple[tuple[str, str], ...]:
        d = self._deployments
        if d is None:
            d = self._deployments = tuple(sorted((g, p) for g in self.graph_names for p in self.deployed_on(g)))
        return d

    def history(self) -> tuple[tuple[str, str, float, float], ...]:
        return tuple(r for r in super().history() if r[0] in self._own_graphs)


class _RobotTrace(Trace):
    """A robot's trace records, tagged with the robot, written to the fleet's file (if any)."""

    def __init__(self, out: IO[str] | None, robot: str) -> None:
        super().__init__(out, keep=False)
        self.robot = robot

    def emit(self, t: float, type_: str, **fields: Any) -> None:
        if self.out is None:
            self.count += 1
            return
        super().emit(t, type_, robot=self.robot, **fields)


#: why an edge server refuses a start (its admission control; the deployer sees a failed start)
EDGE_FULL = "edge server full"


class _Admission:
    """The one Control semantics (:class:`~desmon.deployment.control.ControlRules`) plus
    an edge server's admission control: a start there is refused when, at the moment it
    would run, the detector's Capacity no longer fits beside what runs there already
    (every robot's detectors and the background load)."""

    __slots__ = ("rules", "view", "edges")

    def __init__(self, rules: Any, view: RobotView, edges: frozenset[str]) -> None:
        self.rules = rules
        self.view = view
        self.edges = edges

    def input_devices(self, graph: str, platform: str) -> Any:
        return self.rules.input_devices(graph, platform)

    def start_refusal(self, graph: str, platform: str, state_of: Any) -> str | None:
        why = self.rules.start_refusal(graph, platform, state_of)
        if why is not None or platform not in self.edges:
            return why
        spec = self.view.deployment_information(graph)
        if spec is None:
            return None
        state = self.view.platform_state(platform)
        for req in spec.requirements:
            if isinstance(req, Capacity):
                cap = state.platform.capacity(req.resource)
                if cap is None:
                    continue
                used = state.load_of(req.resource) + sum(a for _g, a in state.used_by(req.resource, excluding=graph))
                if not fits(used + req.amount, cap):
                    return f"{EDGE_FULL}: {cap - used:g} {req.resource} free, {graph} needs {req.amount:g}"
        return None


class _OwnView(SystemView):
    """A robot's SystemView: the platforms' full facts (so ``no-overcommit`` counts
    every robot's detectors on an edge server), but as *its* deployments only those of
    graphs it specifies (another robot's detector is not its to judge)."""

    __slots__ = ()

    @property
    def deployments(self) -> tuple[tuple[str, str], ...]:
        d = self._deployments
        if d is None:  # computed once per view (several invariants read it)
            mine = {s.graph for s in self.specs}
            d = tuple(sorted((g, s.name) for s in self.states for g, _use in s.deployed if g in mine))
            object.__setattr__(self, "_deployments", d)
        return d


class _Member:
    """One robot of the fleet: the parts of a robot's world (:mod:`desmon.sim.parts`) on
    the shared environment and repository, read through its :class:`RobotView`, its
    edge servers behind their admission control, its audit on its own deployments."""

    def __init__(
        self, scenario: Scenario, *, env: simpy.Environment, repo: Repository, view: RobotView, deployer: str, seed: int,
        horizon: float, trace: Trace, edges: tuple[str, ...] = (), admission: bool = True, guard: Any = None,
    ) -> None:
        self.model = scenario.model
        self.query = view
        self.edges = frozenset(edges)
        rules = (lambda control: _Admission(control, view, self.edges)) if admission else None
        self.parts: RobotParts = robot_parts(
            scenario, scenario.world, env=env, repo=repo, query=view, deployer=deployer, seed=seed, horizon=horizon,
            signals=False, trace=trace, rules=rules, keep_decisions=False, guard=guard,
        )
        self.deployer_name = self.parts.core.deployer.name
        #: what the fleet's router tells the robot: Notify, a DEPLOYMENT_HISTORY edge written
        self.notify = self.parts.inbox.notify
        self.count_history = self.parts.books.count_history
        #: memory (MB) a running instance of each of its graphs consumes
        self.consumes = self.parts.facts.consumes

    @property
    def violations(self) -> list[tuple[float, str, str]]:
        return self.parts.books.violations

    def start(self) -> None:
        """The initial facts, silently, and the robot's processes (SimWorld.run without
        running the environment)."""
        apply_initial(self.parts)
        for slip in self.parts.truth.slips:  # the ground truth, ahead of its time (as a robot's own trace has it)
            self.parts.trace.emit(slip.time, "slip", direction=slip.direction, kind=slip.kind)
        start_processes(self.parts, self.audit)

    def audit(self, after: str = "", skip: frozenset[str] = frozenset(), started: tuple[str, str] | None = None) -> tuple[str, ...]:
        """The named invariants on this robot's view (:data:`~desmon.sim.driver.Audit`): its
        own deployments, judged on the platforms' full facts (an edge server's capacity
        with every robot's detectors)."""
        parts = self.parts
        core = parts.core
        view = _OwnView(
            self._audited_states(), core.specs(), core.standing, core.slots(), tuple(sorted(parts.facts.instances)),
            parts.infra.stops, parts.books.history_edges, core.guarded_react, self.query.checks,
        )
        return audit(parts, view, after, skip, started)

    def _audited_states(self) -> tuple[PlatformState, ...]:
        """The states the audit reads: the robot's own PCs and the edge servers where one of
        its detectors runs. An edge server without one holds nothing this robot's
        invariants judge, and it cannot be over-committed by a start of this robot: the
        robot whose start over-commits it audits it at its own next quiescent point."""
        edges = self.edges
        mine = {p for (_g, p) in self.parts.facts.instances if p in edges}
        return tuple(s for s in self.query.platform_states() if s.name not in edges or s.name in mine)

    def finish(self, now: float) -> dict[str, Any]:
        parts = self.parts
        parts.exposure.close(now)
        parts.memory.close(now)
        m = robot_metrics(parts)
        m["audits"] = parts.books.audits
        # a robot's meter sees its own detectors only: an edge server's peak and time over
        # capacity are the fleet's (edge_memory_share_peak, the no-overcommit audit), not its
        for key in ("memory_peak_mb", "overcommit_s"):
            m[key] = {p: v for p, v in m[key].items() if p not in self.edges}
        return m


class _EdgeMeter:
    """Memory in use by detectors on each edge server, integrated over time."""

    def __init__(self, capacity: dict[str, float]) -> None:
        self.capacity = capacity
        self.used = {e: 0.0 for e in capacity}
        self.count = {e: 0 for e in capacity}
        self.since = {e: 0.0 for e in capacity}
        self.integral = {e: 0.0 for e in capacity}
        self.busy = {e: 0.0 for e in capacity}
        self.peak = {e: 0.0 for e in capacity}
        self.starts = {e: 0 for e in capacity}

    def change(self, edge: str, t: float, memory: float, delta: int) -> None:
        dt = t - self.since[edge]
        self.integral[edge] += self.used[edge] * dt
        if self.count[edge]:
            self.busy[edge] += dt
        self.since[edge] = t
        self.used[edge] += memory * delta
        self.count[edge] += delta
        self.peak[edge] = max(self.peak[edge], self.used[edge])
        if delta > 0:
            self.starts[edge] += 1

    def close(self, t: float) -> None:
        for e in self.capacity:
            self.change(e, t, 0.0, 0)


@dataclass
class FleetResult:
    """What a fleet run produced: per-robot metrics and the fleet's."""

    scenario: Scenario
    fleet: Fleet
    deployer: str
    seed: int
    horizon: float
    robots: dict[str, dict[str, Any]]
    metrics: dict[str, Any]
    violations: list[tuple[float, str, str, str]] = field(default_factory=list)  # (t, robot, invariant, message)
    wall_s: float = 0.0


def _edge_sources(sc: Scenario, edges: set[str]) -> list[tuple[str, str]]:
    """What in robot scenario ``sc`` sets a shared edge server's presence or load: (edge, what)."""
    w = sc.world
    named = [(m.component, "an MTTF") for m in w.stochastic_faults]
    named += [(getattr(te.event, "platform", None), f"the scripted '{te.event}'") for te in (*w.faults, *w.loads)]
    named += [(x.platform, "a load walk") for x in w.load_walks] + [(x.platform, "load steps") for x in w.load_steps]
    named += [(getattr(ev, "platform", None), f"the initial '{ev}'") for ev in sc.initial if getattr(ev, "role", "") in ("fault", "load")]
    return [(e, what) for e, what in named if e in edges]


def _check_edge_masters(robots: Sequence[Scenario], edges: set[str]) -> None:
    """An edge server is one machine: its failures and its load are set in one robot's
    scenario, not in several (two MTTFs would fail it twice as often as either says, two
    initial loads would leave one of them silently unused). Robots that state the same
    initial fact of it agree: that is one fact."""
    first: dict[str, tuple[str, str]] = {}
    for sc in robots:
        for e, what in _edge_sources(sc, edges):
            robot, before = first.setdefault(e, (sc.model.robot, what))
            if robot != sc.model.robot and not (what == before and what.startswith("the initial")):
                raise ScenarioError(
                    f"fleet: edge server {e!r} is one machine, but robot {robot!r} sets it ({before}) and robot "
                    f"{sc.model.robot!r} too ({what}): give its failures and loads in one robot's scenario"
                )


def robot_seed(seed: int, robot: str) -> int:
    """The seed of one robot of a run with ``seed``: derived from both, stable across runs."""
    return random.Random(f"{seed}:{robot}").getrandbits(31)


class FleetWorld:
    """One simulation of a fleet scenario (see the module docstring)."""

    def __init__(
        self,
        scenario: Scenario,
        *,
        deployer: str = "desmon",
        seed: int = 0,
        until: float | None = None,
        trace: IO[str] | None = None,
        progress: Callable[[float, float], None] | None = None,
        guard: Any = None,
    ) -> None:
        if not is_fleet(scenario):
            raise ScenarioError(f"scenario {scenario.name!r} is no fleet: its world is not a desmon.sim.fleet.Fleet")
        self.scenario = scenario
        self.fleet: Fleet = scenario.world
        self.seed = int(seed)
        self.horizon = float(until if until is not None else self.fleet.horizon)
        self.progress = progress
        self.trace_out = trace
        self.env = simpy.Environment()
        env = self.env
        self.repo = Repository(clock=lambda: env.now)
        self.cache = _StateCache(self.repo)
        #: the robots' Checks port: columns for many platforms; for a robot's few, each
        #: platform's part memoised on its state's identity (most of a robot's platforms
        #: are unchanged between its questions); no whole answer memoised (a fleet's
        #: states tuples seldom recur)
        self.checks = MemoChecks(PlatformMemoColumnChecks(), answers=False)
        edges = self.fleet.edges
        edge_set = set(edges)
        #: platform -> the robots it concerns; deployment node -> its robot; robot node -> its robot
        self._owners: dict[str, list[_Member]] = {}
        self._graph_owner: dict[str, _Member] = {}
        self._robot_of: dict[str, _Member] = {}
        self.members: list[_Member] = []
        for sc in self.fleet.robots:
            load_model(self.repo, sc.model)  # an edge server already there is only updated (same facts)
        for sc in self.fleet.robots:
            m = sc.model
            own = tuple(p.name for p in m.platforms if p.name not in edge_set)
            view = RobotView(self.repo, m.robot, own, edges, tuple(g.name for g in m.graphs), self.cache, self.checks)
            member = _Member(
                sc, env=env, repo=self.repo, view=view, deployer=deployer, seed=robot_seed(self.seed, m.robot),
                horizon=self.horizon, trace=_RobotTrace(trace, m.robot), edges=edges, admission=self.fleet.admission, guard=guard,
            )
            self.members.append(member)
            for p in own:
                self._owners[p] = [member]
            for g in m.graphs:
                self._graph_owner[node_id(L.DEPLOYMENT, g.name)] = member
            self._robot_of[node_id(L.ROBOT, m.robot)] = member
        for e in edges:
            self._owners[e] = list(self.members)
        first = self.fleet.robots[0].model
        self.edge_meter = _EdgeMeter({e: first.platform(e).capacity_or_unbounded("memory") for e in edges})
        self._edge_ids = {node_id(L.PLATFORM, e): e for e in edges}
        self._consumes = {g: mem for mb in self.members for g, mem in mb.consumes.items()}
        self.deployer_name = self.members[0].deployer_name

    # ------------------------------------------------------------------ Notify, routed
    def _route(self, change: Change) -> None:
        label = change.label
        if label == L.IN_CONTEXT:
            mb = self._robot_of.get(change.source)  # type: ignore[arg-type]
            if mb is not None:
                mb.notify(change)
            return
        if label == L.HAS_DEVICE:
            name = change.source.partition(":")[2]  # type: ignore[union-attr]
            self.cache.mark(name)
            for mb in self._owners.get(name, ()):
                mb.notify(change)
            return
        if label == L.PLATFORM:
            if change.op == UPDATE_NODE:
                name = change.node.partition(":")[2]  # type: ignore[union-attr]
                self.cache.mark(name)
                for mb in self._owners.get(name, ()):
                    mb.notify(change)
            return
        if label == L.DEPLOYMENT:
            if change.op == UPDATE_NODE:  # a requirement change: what deployments consume
                self.cache.mark_all()
                for mb in self.members:
                    mb.query.forget_deployments()
            return
        if L.DEPLOYED_ON in (label, change.old_label):
            name = change.target.partition(":")[2]  # type: ignore[union-attr]
            self.cache.mark(name)
            edge = self._edge_ids.get(change.target)  # type: ignore[arg-type]
            if edge is not None:
                graph = change.source.partition(":")[2]  # type: ignore[union-attr]
                self.edge_meter.change(edge, self.env.now, self._consumes.get(graph, 0.0), 1 if change.op == ADD_EDGE else -1)
            mb = self._graph_owner.get(change.source)  # type: ignore[arg-type]
            if mb is not None:
                mb.query.forget_deployments(change.source.partition(":")[2])  # type: ignore[union-attr]
                if label == L.DEPLOYMENT_HISTORY:
                    mb.count_history(change)

    def _progress(self):  # type: ignore[no-untyped-def]
        step = max(self.horizon / 100.0, 1.0)
        while True:
            yield self.env.timeout(step)
            if self.progress is not None:
                self.progress(self.env.now, self.horizon)

    # ------------------------------------------------------------------ run
    def run(self) -> FleetResult:
        t0 = time.perf_counter()
        for mb in self.members:
            mb.start()  # initial facts, silently: the router is not wired yet
        self.cache.mark_all()
        self.repo.subscribe(self._route)
        if self.progress is not None:
            self.env.process(self._progress())
        with collector_relaxed():  # a fleet's heap is large: full collections cost about a quarter of the run
            self.env.run(until=self.horizon)
        now = self.horizon
        self.edge_meter.close(now)
        robots = {mb.model.robot: mb.finish(now) for mb in self.members}
        violations = [(t, mb.model.robot, name, msg) for mb in self.members for t, name, msg in mb.violations]
        violations.sort(key=lambda v: (v[0], v[1]))
        wall = time.perf_counter() - t0
        metrics = self._metrics(robots, wall, len(violations))
        return FleetResult(self.scenario, self.fleet, self.deployer_name, self.seed, self.horizon, robots, metrics, violations, wall)

    def _metrics(self, robots: dict[str, dict[str, Any]], wall: float, violations: int) -> dict[str, Any]:
        exposure = [m["unmonitored_exposure_s"] for m in robots.values()]
        risky = [m["risky_time_s"] for m in robots.values()]
        errors: dict[str, int] = {}
        for m in robots.values():
            for k, n in m["errors"].items():
                errors[k] = errors.get(k, 0) + n
        em = self.edge_meter
        h = self.horizon
        # (a share of no capacity declared, or of a declared 0 MB, which nothing that needs memory fits: 0)
        share = {e: (em.integral[e] / h / em.capacity[e] if 0 < em.capacity[e] < math.inf else 0.0) for e in em.capacity}
        peak = {e: (em.peak[e] / em.capacity[e] if 0 < em.capacity[e] < math.inf else 0.0) for e in em.capacity}
        total = lambda key: sum(m[key] for m in robots.values())  # noqa: E731
        out: dict[str, Any] = {
            "robots": len(robots),
            "edges": len(em.capacity),
            "horizon_s": h,
            "exposure_per_robot_s": {**_spread(exposure), "interval": _mean_interval(exposure, h)},
            "risky_time_per_robot_s": _spread(risky),
            "exposure_by_cause_per_robot_s": {c: _spread([m["unmonitored_by_cause_s"][c] for m in robots.values()]) for c in CAUSES},
            "excluded_per_robot_s": _spread([m.get("excluded_s", 0.0) for m in robots.values()]),
            "edge_memory_share_mean": _spread(list(share.values())),
            "edge_memory_share_peak": _spread(list(peak.values())),
            "edge_busy_s": _spread(list(em.busy.values())),
            "edge_starts": sum(em.starts.values()),
            "errors": dict(sorted(errors.items())),
            "violations": violations,
            "reactions": total("reactions"),
            "audits": total("audits"),
            "starts": total("starts"),
            "start_failures": total("start_failures"),
            "stops": total("stops"),
            "migrations": total("migrations"),
            "slips_injected": total("slips_injected"),
            "repository_changes": len(self.repo._log),
            "state_reads": self.cache.reads,
            "wall_s": round(wall, 3),
            "realtime_ratio": round(h / wall, 1) if wall > 0 else math.inf,
            "peak_rss_mb": round(peak_rss_mb(), 1),
        }
        return out


def _spread(values: list[float]) -> dict[str, float]:
    """mean, min and max of ``values`` (rounded), as the reports print them."""
    if not values:
        return {"mean": 0.0, "min": 0.0, "max": 0.0}
    return {"mean": round(sum(values) / len(values), 6), "min": round(min(values), 6), "max": round(max(values), 6)}


#: the confidence of the interval of a fleet's mean exposure per robot (as desmon sweep-plot's)
FLEET_CONFIDENCE = 0.95


def _mean_interval(values: list[float], horizon: float) -> dict[str, Any] | None:
    """The interval of the mean of the robots' ``values`` (None from fewer than 2): the normal
    approximation inside ``[0, horizon]``, not the betting interval, though the values lie in
    that range: its guarantee needs independent, alike runs, and a fleet's robots share the
    edge servers and differ in their idle times."""
    if len(values) < 2:
        return None
    from desmon.stats import normal_interval

    iv = normal_interval(values, 1.0 - FLEET_CONFIDENCE, (0.0, horizon))
    return {
        "low": round(iv.low, 6), "high": round(iv.high, 6), "confidence": FLEET_CONFIDENCE,
        "method": f"normal approximation over the {len(values)} robots, not guaranteed: they share the edge servers, and a rare "
                  "long exposure of a few robots can leave the fleet's mean outside it (docs/fleet.md)",
    }


def peak_rss_mb() -> float:
    """The process's peak resident memory so far, in MB (getrusage maxrss)."""
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return rss / (1024.0 * 1024.0) if sys.platform == "darwin" else rss / 1024.0


def simulate_fleet(scenario: Scenario, deployer: str = "desmon", seed: int = 0, **kw: Any) -> FleetResult:
    """Run the fleet ``scenario`` in the SimPy world and return the result."""
    return FleetWorld(scenario, deployer=deployer, seed=seed, **kw).run()
