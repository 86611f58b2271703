"""Inserting the model and run-time facts into the repository.

Design-time knowledge (:func:`load_model`) and the run-time facts the context monitor
and the infrastructure write: current context, device loss / repair (the HAS_DEVICE
edge), platform up / down, background load, and deployments started / stopped
(DEPLOYED_ON, relabelled DEPLOYMENT_HISTORY with start and stop times).
"""

from __future__ import annotations

from typing import Callable

from desmon.errors import QueryError
from desmon.model.events import RequirementChange
from desmon.model.requirements import DeploymentSpec
from desmon.model.system import SystemModel, with_load
from desmon.repository import labels as L
from desmon.repository.store import Repository, node_id

__all__ = [
    "load_model",
    "set_context",
    "set_device_working",
    "set_platform_up",
    "set_load",
    "change_requirements",
    "record_start",
    "record_stop",
    "RepositoryInsert",
    "ImmediateControl",
]


def load_model(repo: Repository, model: SystemModel) -> None:
    """Translate a validated model into nodes and edges (the paper's RPSL/DepSL import)."""
    for p in model.platforms:
        repo.add_node(
            L.PLATFORM,
            p.name,
            platform=p,
            capacities=dict(p.capacities),
            attributes=dict(p.attributes),
            properties=dict(p.properties),
            up=not p.on_demand,  # an on-demand platform is absent until it joins
            load={},
        )
    for d in model.devices:
        dev = repo.add_node(L.DEVICE, d.name, device=d, kind=d.kind, vendor=d.vendor, version=d.version, working=True)
        repo.add_edge(node_id(L.PLATFORM, d.platform), dev, L.HAS_DEVICE)
    for g in model.graphs:
        repo.add_node(
            L.PERCEPTION_GRAPH,
            g.name,
            components=[c.name for c in g.components],
            reads=list(g.device_kinds),
        )
    for spec in model.specs:
        dep = repo.add_node(L.DEPLOYMENT, spec.graph, spec=spec, declared=spec)
        repo.add_edge(dep, node_id(L.PERCEPTION_GRAPH, spec.graph), L.RESOLVES)
        for req in spec.requirements:
            _add_requirement(repo, dep, spec.graph, req)
        if spec.fixed_platform is not None:
            repo.add_edge(dep, node_id(L.PLATFORM, spec.fixed_platform), L.EXECUTABLE_ON)
    repo.add_node(L.ROBOT, model.robot)


def _add_requirement(repo: Repository, dep: str, graph: str, req: object) -> None:
    """A REQUIREMENT node ``graph#i`` (the first free i: removed requirements keep their
    nodes, as history) and the REQUIRES edge to it."""
    i = 0
    while node_id(L.REQUIREMENT, f"{graph}#{i}") in repo.node_data:
        i += 1
    rid = repo.add_node(L.REQUIREMENT, f"{graph}#{i}", kind=type(req).__name__, description=req.describe(), requirement=req)  # type: ignore[attr-defined]
    repo.add_edge(dep, rid, L.REQUIRES)


def change_requirements(repo: Repository, change: RequirementChange) -> tuple[str, ...] | None:
    """Apply ``change`` to the deployment node of its graph: a removed requirement loses
    its REQUIRES edge (the node stays, as history), an added one gets a new node. The
    node's specification (what a deployment consumes) follows. Returns the platforms the
    graph is deployed on (so they are re-checked), or None if nothing changed."""
    dep = node_id(L.DEPLOYMENT, change.graph)
    if dep not in repo.node_data:
        raise QueryError(f"{change}: no deployment specification for {change.graph!r} in the repository")
    spec: DeploymentSpec = repo.node_data[dep]["spec"]
    new = change.apply(spec.requirements, repo.node_data[dep]["declared"].requirements)
    if new == spec.requirements:
        return None
    for rid in repo.successors(dep, L.REQUIRES):
        if repo.node_data[rid]["requirement"] not in new:  # removed, or a Capacity an added one replaces
            repo.remove_edge(dep, rid, L.REQUIRES)
    for req in new:
        if req not in spec.requirements:
            _add_requirement(repo, dep, change.graph, req)
    repo.update_node(dep, spec=DeploymentSpec(change.graph, new, spec.fixed_platform, spec.rebalance, spec.reads))
    repo.specs_version += 1
    return tuple(repo.node_data[p]["name"] for p in repo.successors(dep, L.DEPLOYED_ON))


def set_context(repo: Repository, robot: str, context: str) -> bool:
    """Point the robot's IN_CONTEXT edge at ``context``; False if it already did."""
    rid = node_id(L.ROBOT, robot)
    cid = node_id(L.CONTEXT, context)
    current = repo.successors(rid, L.IN_CONTEXT)  # indexed: no scan of the robot's other edges
    if current == [cid]:
        return False
    if cid not in repo.node_data:
        repo.add_node(L.CONTEXT, context)
    for t in current:
        repo.remove_edge(rid, t, L.IN_CONTEXT)
    repo.add_edge(rid, cid, L.IN_CONTEXT)
    return True


def _device_home(repo: Repository, device: str) -> tuple[str, str]:
    did = node_id(L.DEVICE, device)
    if did not in repo.node_data:
        raise QueryError(f"unknown device {device!r}: it is not in the repository")
    return did, node_id(L.PLATFORM, repo.node_data[did]["device"].platform)


def set_device_working(repo: Repository, device: str, working: bool) -> str | None:
    """Remove (failure) or restore (repair) the HAS_DEVICE edge; returns the changed platform."""
    did, pid = _device_home(repo, device)
    if repo.node_data[did]["working"] == working:
        return None
    repo.update_node(did, working=working)
    if working:
        repo.add_edge(pid, did, L.HAS_DEVICE)
    else:
        repo.remove_edge(pid, did, L.HAS_DEVICE)
    return repo.node_data[pid]["name"]


def _platform(repo: Repository, platform: str) -> str:
    pid = node_id(L.PLATFORM, platform)
    if pid not in repo.node_data:
        raise QueryError(f"unknown platform {platform!r}: it is not in the repository")
    return pid


def set_platform_up(repo: Repository, platform: str, up: bool) -> bool:
    """Record a platform crash (``up=False``) or reboot; False if nothing changed."""
    pid = _platform(repo, platform)
    if repo.node_data[pid]["up"] == up:
        return False
    repo.update_node(pid, up=up)
    return True


def set_load(repo: Repository, platform: str, resource: str, amount: float) -> bool:
    """Record the background (non-monitor) consumption of ``resource``; False if unchanged."""
    pid = _platform(repo, platform)
    load = with_load(repo.node_data[pid]["load"], resource, amount)
    if load is None:
        return False
    repo.update_node(pid, load=load)
    return True


def record_start(repo: Repository, graph: str, platform: str) -> None:
    """The infrastructure started ``graph`` on ``platform``: a DEPLOYED_ON edge."""
    repo.add_edge(node_id(L.DEPLOYMENT, graph), _platform(repo, platform), L.DEPLOYED_ON, start=repo.now)


def record_stop(repo: Repository, graph: str, platform: str) -> None:
    """The infrastructure stopped ``graph``: DEPLOYED_ON becomes DEPLOYMENT_HISTORY with stop time."""
    repo.relabel_edge(node_id(L.DEPLOYMENT, graph), _platform(repo, platform), L.DEPLOYED_ON, L.DEPLOYMENT_HISTORY, stop=repo.now)


class RepositoryInsert:
    """The Insert facts of the context monitor, written into a :class:`Repository`."""

    def __init__(self, repo: Repository, robot: str) -> None:
        self.repo = repo
        self.robot = robot

    def set_context(self, context: str) -> bool:
        return set_context(self.repo, self.robot, context)

    def set_device_working(self, device: str, working: bool) -> str | None:
        return set_device_working(self.repo, device, working)

    def set_platform_up(self, platform: str, up: bool) -> bool:
        return set_platform_up(self.repo, platform, up)

    def set_load(self, platform: str, resource: str, amount: float) -> bool:
        return set_load(self.repo, platform, resource, amount)

    def change_requirements(self, change: RequirementChange) -> tuple[str, ...] | None:
        return change_requirements(self.repo, change)


class ImmediateControl:
    """An infrastructure whose start/stop take no time: the scripted driver's Control port.

    ``refuse(graph, platform)`` gives the reason the infrastructure refuses a start, or
    None: the engines pass the one Control semantics of
    :class:`desmon.deployment.control.ControlRules` (build it with
    :func:`desmon.deployment.control.repository_control`); without it no start is refused.
    ``fails`` decides whether a start that is not refused fails anyway
    (``fails(graph, platform) -> bool``). Starting an instance that already runs is a
    no-op success. It keeps its own list of running instances (``running``) and a stop
    count, so the ``history`` invariant can compare them with the repository's edges.
    """

    def __init__(
        self,
        repo: Repository,
        fails: Callable[[str, str], bool] | None = None,
        refuse: Callable[[str, str], str | None] | None = None,
    ) -> None:
        self.repo = repo
        self.fails = fails or (lambda g, p: False)
        self.refuse = refuse
        self.running: set[tuple[str, str]] = set()
        self.stops = 0
        #: why the last start was refused ("" when it was not)
        self.refused = ""
        #: called as ``after(verb, graph, platform)`` once a start of an instance that was not
        #: running or a stop has succeeded (None: not watched): the engines' audit of the
        #: instantaneous invariants
        self.after: Callable[[str, str, str], None] | None = None

    def start(self, graph: str, platform: str) -> bool:
        restart = (graph, platform) in self.running  # (a no-op: it changes nothing to audit)
        ok = self._start(graph, platform)
        if ok and not restart and self.after is not None:
            self.after("start", graph, platform)
        return ok

    def _start(self, graph: str, platform: str) -> bool:
        if (graph, platform) in self.running:
            return True
        why = self.refuse(graph, platform) if self.refuse is not None else None
        self.refused = why or ""
        if why is not None:
            return False
        if self.fails(graph, platform):
            return False
        self.running.add((graph, platform))
        record_start(self.repo, graph, platform)
        return True

    def stop(self, graph: str, platform: str) -> bool:
        if (graph, platform) not in self.running:
            return False
        self.running.discard((graph, platform))
        self.stops += 1
        record_stop(self.repo, graph, platform)
        if self.after is not None:
            self.after("stop", graph, platform)
        return True
