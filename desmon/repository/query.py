"""The Query interface over the networkx repository.

:class:`RepositoryQuery` answers the named queries of Algorithms 1 and 2 (it satisfies
:class:`desmon.deployment.ports.QueryPort` structurally) plus a generic :meth:`match`.
"""

from __future__ import annotations

from typing import Any, Iterator

from desmon.errors import QueryError
from desmon.model.requirements import DeploymentSpec, Requirement, declared_order
from desmon.model.system import PlatformState, new_platform_state
from desmon.repository import labels as L
from desmon.repository.store import Repository, node_id

__all__ = ["RepositoryQuery", "PlatformStateReader"]

# keys of the memoised answers (no graph name is a tuple)
_STATES = ("platform_states",)
_CONTEXT = ("context",)
_DEPLOYMENTS = ("deployments",)
#: platform states kept for handing out equal facts as the same object (cleared past it)
_SEEN = 1 << 14


def _amount_types(load: tuple[tuple[str, float], ...], deployed: tuple[tuple[str, tuple[tuple[str, float], ...]], ...]) -> list[type]:
    """The types of the amounts in a state's ``load`` and ``deployed``: equal numbers of
    another type (1 and 1.0) are other facts, which may print otherwise."""
    return [type(a) for _r, a in load] + [type(a) for _g, use in deployed for _r, a in use]


class PlatformStateReader:
    """The platform states of a :class:`Repository`, memoised on what each reads (the
    query's part that builds :class:`PlatformState` objects)."""

    def __init__(self, repo: Repository) -> None:
        self.repo = repo
        # every state handed out (bounded): equal facts are handed out as one object, on
        # whose identity readers (the validity memo, the checks' parts) memoise. Keyed on
        # (id of the platform, up, id of the devices tuple, load, deployed): the platform
        # object is its node's, and equal device lists are one tuple (_devices), so the
        # key is hashed and compared without a Python-level __hash__ or __eq__; the state
        # an entry holds keeps the objects its ids name alive
        self._seen_states: dict[tuple[Any, ...], tuple[PlatformState, list[type]]] = {}  # (the state, _amount_types of it)
        # ids of a platform's working devices, in order -> the one tuple of them handed out
        self._devices: dict[tuple[int, ...], tuple[Any, ...]] = {}
        # platform -> (the stamps it was read at, its state)
        self._state_memo: dict[str, tuple[tuple[int | None, ...], PlatformState]] = {}
        # platform node -> (stamps, its devices, stamps, its deployments, the types of
        # their amounts): parts of its state
        self._state_parts: dict[str, tuple[Any, tuple[Any, ...], Any, tuple[Any, ...], list[type]]] = {}
        # platform node -> (its load dict, that dict's sorted items, the types of their
        # amounts): a load write puts a new dict on the node (desmon.model.system.with_load),
        # so the same dict object has the same items; the entry keeps the dict alive
        self._loads: dict[str, tuple[dict[str, Any], tuple[tuple[str, Any], ...], list[type]]] = {}
        # id of a deployment spec -> (the spec, its consumption()): specs are frozen
        self._uses: dict[int, tuple[DeploymentSpec, tuple[tuple[str, float], ...]]] = {}

    def state_of(self, pid: str, platform: str) -> PlatformState:
        """:meth:`RepositoryQuery.platform_state` of node ``pid``, memoised on what it
        reads: the platform node's stamp (its attributes, and its HAS_DEVICE and
        DEPLOYED_ON edges, which touch it) and the last node change of any device and any
        deployment (their attributes)."""
        repo = self.repo
        stamp = repo.touched.get(pid)
        if stamp is None:  # every node added has a stamp, and nodes are never removed
            raise QueryError(f"unknown platform {platform!r}")
        updated = repo.label_updated
        key = (stamp, updated.get(L.DEVICE), updated.get(L.DEPLOYMENT))
        hit = self._state_memo.get(platform)
        if hit is not None and hit[0] == key:
            return hit[1]
        state = self._read_state(pid)
        self._state_memo[platform] = (key, state)
        return state

    def _read_state(self, pid: str) -> PlatformState:
        """The facts of platform node ``pid`` (the object handed out before for equal
        facts); its devices and its deployments are re-read only when its HAS_DEVICE /
        DEPLOYED_ON edges or a device / deployment node changed."""
        repo = self.repo
        nodes = repo.node_data
        data = nodes[pid]
        edges, updated = repo.edge_touched, repo.label_updated
        parts = self._state_parts.get(pid)
        dkey = (edges.get((pid, L.HAS_DEVICE)), updated.get(L.DEVICE))
        if parts is not None and parts[0] == dkey:
            devices = parts[1]
        else:
            devs = repo.successors(pid, L.HAS_DEVICE)
            devices = tuple(nodes[d]["device"] for d in sorted(devs, key=lambda d: nodes[d]["order"]))
            ids = tuple(map(id, devices))
            known = self._devices.get(ids)
            if known is not None:
                devices = known  # the same devices as before: the same tuple (the seen states' key)
            else:
                if len(self._devices) > _SEEN:
                    self._devices.clear()
                self._devices[ids] = devices  # the tuple keeps the devices its key names alive
        gkey = (edges.get((pid, L.DEPLOYED_ON)), updated.get(L.DEPLOYMENT))
        if parts is not None and parts[2] == gkey:
            deployed, used = parts[3], parts[4]
        else:
            deployed = tuple(sorted((nodes[d]["name"], self._consumption(d)) for d in repo.predecessors(pid, L.DEPLOYED_ON)))
            used = _amount_types((), deployed)
        self._state_parts[pid] = (dkey, devices, gkey, deployed, used)
        raw = data["load"]
        loads = self._loads.get(pid)
        if loads is None or loads[0] is not raw:
            load = tuple(sorted(raw.items()))
            loads = self._loads[pid] = (raw, load, _amount_types(load, ()))
        platform, up, load = data["platform"], bool(data["up"]), loads[1]
        seen = self._seen_states
        facts = (id(platform), up, id(devices), load, deployed)
        got = seen.get(facts)
        types = loads[2] + used  # _amount_types(load, deployed)
        if got is not None and got[1] == types:
            return got[0]  # facts seen before: the object handed out then
        if len(seen) > _SEEN:
            seen.clear()
        state = new_platform_state(platform, up, devices, load, deployed)
        seen[facts] = (state, types)
        return state

    def _consumption(self, dep: str) -> tuple[tuple[str, float], ...]:
        """``spec.consumption()`` of deployment node ``dep`` (() without a spec), kept per spec object."""
        spec = self.repo.node_data[dep].get("spec")
        if spec is None:
            return ()
        uses = self._uses
        hit = uses.get(id(spec))
        if hit is not None and hit[0] is spec:
            return hit[1]
        use = spec.consumption()
        if len(uses) > _SEEN:
            uses.clear()
        uses[id(spec)] = (spec, use)
        return use


class RepositoryQuery:
    """Named queries over a :class:`Repository`.

    ``checks`` is the Checks port requirement questions about its platforms go to
    (:class:`desmon.deployment.ports.ChecksPort`, chosen by whoever builds the port;
    None: the default memoised checks)."""

    def __init__(self, repo: Repository, checks: Any = None) -> None:
        self.repo = repo
        self.checks = checks
        #: validity answers memoised on the identity of :meth:`platform_states`' tuple,
        #: which is the same object while no platform's facts changed (see
        #: :func:`desmon.deployment.validity.validity_for`)
        self.validity_memo: dict | None = {}
        self._reader = PlatformStateReader(repo)
        self._state_of = self._reader.state_of
        # the platforms' (node id, name), in declaration order, and the ids they were read for
        self._platforms: tuple[tuple[str, ...], tuple[tuple[str, str], ...]] = ((), ())
        # ids of the states of a platform_states answer -> the tuple of them handed out
        self._tuples: dict[tuple[int, ...], tuple[PlatformState, ...]] = {}
        # graph -> (what its spec was read from, the node's spec object, the spec, (graph
        # node, deployment node), the stamps of what it read: see _spec_key)
        self._spec_memo: dict[str, tuple[tuple[Any, ...], Any, DeploymentSpec, tuple[str, str], tuple[int | None, ...]]] = {}
        # answers that hold while no node of some labels is touched: {question: (stamps, answer)}
        self._stamped: dict[Any, tuple[Any, Any]] = {}
        # deployment node -> (the stamps they were read at, its fixed platform / its requirements)
        self._fixed_memo: dict[str, tuple[int | None, str | None]] = {}
        self._constraints_memo: dict[str, tuple[tuple[int | None, ...], tuple[Requirement, ...]]] = {}
        self._on_memo: tuple[int | None, dict[str, tuple[str, ...]]] = (-1, {})

    @property
    def _g(self):  # type: ignore[no-untyped-def]
        """The networkx graph, every change applied (for its edges: the questions it alone answers)."""
        return self.repo.graph

    @property
    def _nodes(self):  # type: ignore[no-untyped-def]
        """Every node's attributes, by id (no edge change applied for it)."""
        return self.repo.node_data

    def _out(self, nid: str, label: str) -> list[str]:
        return self.repo.successors(nid, label)

    def _in(self, nid: str, label: str) -> list[str]:
        return self.repo.predecessors(nid, label)

    @property
    def specs_version(self) -> int:
        """Changes with every run-time requirement change (see ``DeploymentCore.specs``)."""
        return self.repo.specs_version

    # -- the algorithms' queries ---------------------------------------------------------
    def deployment_information(self, graph: str) -> DeploymentSpec | None:
        """The deployment node RESOLVING ``graph`` as a spec, or None (Alg. 1 line 3).

        Memoised on what it reads: the RESOLVES edges of the graph's node, the deployment
        node's attributes (its spec object) and its REQUIRES and EXECUTABLE_ON edges, and
        the requirement nodes' attributes; the same spec object comes back while none of
        them changed (and while the spec read from them is equal)."""
        repo = self.repo
        hit = self._spec_memo.get(graph)
        if hit is not None and self._spec_key(hit[3]) == hit[4]:
            return hit[2]
        gid = node_id(L.PERCEPTION_GRAPH, graph)
        if gid not in self._nodes:
            return None
        deps = self._in(gid, L.RESOLVES)
        if not deps:
            return None
        dep = deps[0]
        touched = repo.touched
        reqs = self._out(dep, L.REQUIRES)
        key = (dep, tuple(reqs), tuple([touched[r] for r in reqs]), tuple(self._out(dep, L.EXECUTABLE_ON)))
        node_spec = self._nodes[dep].get("spec")
        if hit is not None and hit[0] == key and hit[1] is node_spec:
            spec = hit[2]
        else:
            spec = self._read_spec(graph, dep)
        self._spec_memo[graph] = (key, node_spec, spec, (gid, dep), self._spec_key((gid, dep)))
        return spec

    def _spec_key(self, nodes: tuple[str, str]) -> tuple[int | None, ...]:
        """The stamps of what :meth:`deployment_information` reads, for (graph node, deployment node)."""
        gid, dep = nodes
        repo = self.repo
        edges = repo.edge_touched
        return (
            edges.get((gid, L.RESOLVES)), repo.node_updated.get(dep), edges.get((dep, L.REQUIRES)),
            edges.get((dep, L.EXECUTABLE_ON)), repo.label_updated.get(L.REQUIREMENT),
        )

    def _read_spec(self, graph: str, dep: str) -> DeploymentSpec:
        reqs = self._required(dep)
        fixed = self._out(dep, L.EXECUTABLE_ON)
        node_spec = self._nodes[dep].get("spec")
        rebalance = node_spec.rebalance if node_spec is not None else None
        reads = node_spec.reads if node_spec is not None else ()
        return DeploymentSpec(graph, reqs, self._nodes[fixed[0]]["name"] if fixed else None, rebalance, reads)

    def has_fixed_deployment(self, spec: DeploymentSpec) -> bool:
        return self.fixed_platform(spec) is not None

    def fixed_platform(self, spec: DeploymentSpec) -> str | None:
        dep = node_id(L.DEPLOYMENT, spec.graph)
        stamp = self.repo.edge_touched.get((dep, L.EXECUTABLE_ON))
        hit = self._fixed_memo.get(dep)
        if hit is not None and hit[0] == stamp:
            return hit[1]
        fixed = self._out(dep, L.EXECUTABLE_ON)
        name = self._nodes[fixed[0]]["name"] if fixed else None
        self._fixed_memo[dep] = (stamp, name)
        return name

    def constraints(self, spec: DeploymentSpec) -> tuple[Requirement, ...]:
        """The requirements the deployment node of ``spec``'s graph REQUIRES now, in
        order; memoised while none of its REQUIRES edges and no requirement node changed."""
        dep = node_id(L.DEPLOYMENT, spec.graph)
        repo = self.repo
        key = (repo.edge_touched.get((dep, L.REQUIRES)), repo.label_updated.get(L.REQUIREMENT))
        hit = self._constraints_memo.get(dep)
        if hit is not None and hit[0] == key:
            return hit[1]
        reqs = self._required(dep)
        self._constraints_memo[dep] = (key, reqs)
        return reqs

    def _required(self, dep: str) -> tuple[Requirement, ...]:
        """What deployment node ``dep`` REQUIRES, in :func:`~desmon.model.requirements.declared_order`
        of the specification it was inserted with (in insertion order without one): one set of
        requirements reads as one tuple, whatever changes led to it."""
        nodes = self._nodes
        found = [nodes[r]["requirement"] for r in sorted(self._out(dep, L.REQUIRES), key=lambda r: nodes[r]["order"])]
        declared = nodes[dep].get("declared")
        return declared_order(found, declared.requirements) if declared is not None else tuple(found)

    def platform_state(self, platform: str) -> PlatformState:
        """The run-time facts of ``platform``; memoised while no change touched its node,
        its devices or the deployments on it (the same object for the same facts)."""
        return self._state_of(node_id(L.PLATFORM, platform), platform)

    def platform_states(self) -> tuple[PlatformState, ...]:
        """Every platform's run-time facts, in declaration order; memoised while no change
        touches a platform node and no device or deployment node changes (what
        :meth:`platform_state` reads: a HAS_DEVICE or DEPLOYED_ON edge touches its
        platform; devices and deployments are read for their attributes only)."""
        updated = self.repo.label_updated
        key = (self.repo.label_touched.get(L.PLATFORM), updated.get(L.DEVICE), updated.get(L.DEPLOYMENT))
        hit = self._stamped.get(_STATES)
        if hit is not None and hit[0] == key:
            return hit[1]  # type: ignore[no-any-return]
        ids = self.repo.node_ids(L.PLATFORM)
        known = self._platforms
        if known[0] != ids:
            nodes = self._nodes
            known = self._platforms = (ids, tuple((pid, nodes[pid]["name"]) for pid in ids))
        state_of = self._state_of
        states = tuple([state_of(pid, name) for pid, name in known[1]])
        # the same states (facts): the same tuple handed out before, the validity memo's
        # key; the entry holds the tuple, so the ids of its states name those objects
        ids = tuple(map(id, states))
        tuples = self._tuples
        seen = tuples.get(ids)
        if seen is not None:
            states = seen
        else:
            if len(tuples) > _SEEN:
                tuples.clear()
            tuples[ids] = states
        self._stamped[_STATES] = (key, states)
        return states

    def _deployed_memo(self) -> dict[str, tuple[str, ...]]:
        """Answers about DEPLOYED_ON edges, memoised while none changes (they name their
        ends by the nodes' names, which are fixed when a node is added)."""
        stamp = self.repo.edges_changed.get(L.DEPLOYED_ON)
        memo = self._on_memo
        if memo[0] != stamp:
            memo = self._on_memo = (stamp, {})
        return memo[1]

    def deployed_on(self, graph: str) -> tuple[str, ...]:
        current = self._deployed_memo()
        on = current.get(graph)
        if on is None:
            dep = node_id(L.DEPLOYMENT, graph)
            on = current[graph] = tuple(sorted(self._nodes[p]["name"] for p in self._out(dep, L.DEPLOYED_ON))) if dep in self._nodes else ()
        return on

    def is_deployed(self, graph: str, platforms: tuple[str, ...] | None = None) -> bool:
        """isDeployed(g, P): is ``graph`` active on one of ``platforms`` (any, if None)?"""
        on = self.deployed_on(graph)
        return bool(on) if platforms is None else any(p in platforms for p in on)

    def active_deployments(self, platform: str) -> tuple[str, ...]:
        current = self._deployed_memo()
        question = (platform,)  # no graph name is a tuple
        on = current.get(question)  # type: ignore[call-overload]
        if on is None:
            pid = node_id(L.PLATFORM, platform)
            if pid not in self._nodes:
                raise QueryError(f"unknown platform {platform!r}")
            on = current[question] = tuple(sorted(self._nodes[d]["name"] for d in self._in(pid, L.DEPLOYED_ON)))  # type: ignore[index]
        return on  # type: ignore[no-any-return]

    def perception_graph(self, deployment: str) -> str:
        dep = node_id(L.DEPLOYMENT, deployment)
        if dep not in self._nodes:
            raise QueryError(f"unknown deployment {deployment!r}")
        graphs = self._out(dep, L.RESOLVES)
        if not graphs:
            raise QueryError(f"deployment {deployment!r} resolves no perception graph")
        return str(self._nodes[graphs[0]]["name"])

    def context(self) -> str | None:
        """The robot's current context; memoised while no robot node is touched (its
        IN_CONTEXT edge starts there; a context is named by its node's name, fixed when
        the node is added)."""
        stamp = self.repo.label_touched.get(L.ROBOT)
        hit = self._stamped.get(_CONTEXT)
        if hit is not None and hit[0] == stamp:
            return hit[1]  # type: ignore[no-any-return]
        ctx: str | None = None
        for nid in self.repo.node_ids(L.ROBOT):
            out = self._out(nid, L.IN_CONTEXT)
            ctx = str(self._nodes[out[0]]["name"]) if out else None
            break
        self._stamped[_CONTEXT] = (stamp, ctx)
        return ctx

    def deployments(self) -> tuple[tuple[str, str], ...]:
        """Every active (graph, platform) pair, sorted."""
        current = self._deployed_memo()
        out = current.get(_DEPLOYMENTS)  # type: ignore[call-overload]
        if out is None:
            nodes = self._nodes
            out = current[_DEPLOYMENTS] = tuple(sorted((nodes[s]["name"], nodes[t]["name"]) for s, t, _k in self.repo.labelled(L.DEPLOYED_ON)))  # type: ignore[index]
        return out  # type: ignore[return-value]

    def history(self) -> tuple[tuple[str, str, float, float], ...]:
        """Every stopped deployment as (graph, platform, start, stop), in stop order."""
        nodes, edges = self._nodes, self._g.edges
        rows = []
        for s, t, k in self.repo.labelled(L.DEPLOYMENT_HISTORY):
            d = edges[s, t, k]
            rows.append((nodes[s]["name"], nodes[t]["name"], float(d["start"]), float(d["stop"])))
        return tuple(sorted(rows, key=lambda r: (r[3], r[2], r[0], r[1])))

    # -- generic ------------------------------------------------------------------------
    def match(
        self,
        source_label: str | None = None,
        edge_label: str | None = None,
        target_label: str | None = None,
        **where: Any,
    ) -> Iterator[tuple[str, str, dict[str, Any]]]:
        """``(s)-[e]->(t)`` pattern match; ``where`` filters on edge attributes.

        ``match("Deployment", "DEPLOYED_ON", "Platform")`` yields every active deployment edge.
        """
        for s, t, d in self._g.edges(data=True):
            if edge_label is not None and d.get("label") != edge_label:
                continue
            if source_label is not None and self._nodes[s].get("label") != source_label:
                continue
            if target_label is not None and self._nodes[t].get("label") != target_label:
                continue
            if any(d.get(k) != v for k, v in where.items()):
                continue
            yield s, t, d
