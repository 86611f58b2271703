"""The Query interface over the networkx repository.

:class:`RepositoryQuery` answers the named queries of Algorithms 1 and 2 (it satisfies
:class:`desmon.deployment.ports.QueryPort` structurally) plus a generic :meth:`match`.
"""

from __future__ import annotations

from typing import Any, Iterator

from desmon.errors import QueryError
from desmon.model.requirements import DeploymentSpec, Requirement
from desmon.model.system import PlatformState
from desmon.repository import labels as L
from desmon.repository.store import Repository, node_id

__all__ = ["RepositoryQuery"]


class RepositoryQuery:
    """Named queries over a :class:`Repository`.

    ``checks`` is the Checks port requirement questions about its platforms go to
    (:class:`desmon.deployment.ports.ChecksPort`, chosen by whoever builds the port;
    None: the default memoised checks)."""

    #: platform states are rebuilt on every call: nothing to memoise on their identity
    validity_memo = None

    def __init__(self, repo: Repository, checks: Any = None) -> None:
        self.repo = repo
        self.checks = checks

    @property
    def _g(self):  # type: ignore[no-untyped-def]
        return self.repo.graph

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
        """The deployment node RESOLVING ``graph`` as a spec, or None (Alg. 1 line 3)."""
        gid = node_id(L.PERCEPTION_GRAPH, graph)
        if gid not in self._g:
            return None
        deps = self._in(gid, L.RESOLVES)
        if not deps:
            return None
        dep = deps[0]
        reqs = tuple(
            self._g.nodes[r]["requirement"] for r in sorted(self._out(dep, L.REQUIRES), key=lambda r: self._g.nodes[r]["order"])
        )
        fixed = self._out(dep, L.EXECUTABLE_ON)
        declared = self._g.nodes[dep].get("spec")
        rebalance = declared.rebalance if declared is not None else None
        reads = declared.reads if declared is not None else ()
        return DeploymentSpec(graph, reqs, self._g.nodes[fixed[0]]["name"] if fixed else None, rebalance, reads)

    def has_fixed_deployment(self, spec: DeploymentSpec) -> bool:
        return self.fixed_platform(spec) is not None

    def fixed_platform(self, spec: DeploymentSpec) -> str | None:
        fixed = self._out(node_id(L.DEPLOYMENT, spec.graph), L.EXECUTABLE_ON)
        return self._g.nodes[fixed[0]]["name"] if fixed else None

    def constraints(self, spec: DeploymentSpec) -> tuple[Requirement, ...]:
        dep = node_id(L.DEPLOYMENT, spec.graph)
        return tuple(
            self._g.nodes[r]["requirement"] for r in sorted(self._out(dep, L.REQUIRES), key=lambda r: self._g.nodes[r]["order"])
        )

    def _consumption(self, dep: str) -> tuple[tuple[str, float], ...]:
        spec = self._g.nodes[dep].get("spec")
        return spec.consumption() if spec is not None else ()

    def platform_state(self, platform: str) -> PlatformState:
        pid = node_id(L.PLATFORM, platform)
        if pid not in self._g:
            raise QueryError(f"unknown platform {platform!r}")
        data = self._g.nodes[pid]
        devices = tuple(
            self._g.nodes[d]["device"] for d in sorted(self._out(pid, L.HAS_DEVICE), key=lambda d: self._g.nodes[d]["order"])
        )
        deployed = tuple(sorted((self._g.nodes[d]["name"], self._consumption(d)) for d in self._in(pid, L.DEPLOYED_ON)))
        return PlatformState(
            platform=data["platform"],
            up=bool(data["up"]),
            devices=devices,
            load=tuple(sorted(data["load"].items())),
            deployed=deployed,
        )

    def platform_states(self) -> tuple[PlatformState, ...]:
        """Every platform's run-time facts, in declaration order."""
        return tuple(self.platform_state(data["name"]) for _nid, data in self.repo.nodes(L.PLATFORM))

    def deployed_on(self, graph: str) -> tuple[str, ...]:
        dep = node_id(L.DEPLOYMENT, graph)
        if dep not in self._g:
            return ()
        return tuple(sorted(self._g.nodes[p]["name"] for p in self._out(dep, L.DEPLOYED_ON)))

    def is_deployed(self, graph: str, platforms: tuple[str, ...] | None = None) -> bool:
        """isDeployed(g, P): is ``graph`` active on one of ``platforms`` (any, if None)?"""
        on = self.deployed_on(graph)
        return bool(on) if platforms is None else any(p in platforms for p in on)

    def active_deployments(self, platform: str) -> tuple[str, ...]:
        pid = node_id(L.PLATFORM, platform)
        if pid not in self._g:
            raise QueryError(f"unknown platform {platform!r}")
        return tuple(sorted(self._g.nodes[d]["name"] for d in self._in(pid, L.DEPLOYED_ON)))

    def perception_graph(self, deployment: str) -> str:
        dep = node_id(L.DEPLOYMENT, deployment)
        if dep not in self._g:
            raise QueryError(f"unknown deployment {deployment!r}")
        graphs = self._out(dep, L.RESOLVES)
        if not graphs:
            raise QueryError(f"deployment {deployment!r} resolves no perception graph")
        return str(self._g.nodes[graphs[0]]["name"])

    def context(self) -> str | None:
        for _nid, _data in self.repo.nodes(L.ROBOT):
            ctx = self._out(_nid, L.IN_CONTEXT)
            return str(self._g.nodes[ctx[0]]["name"]) if ctx else None
        return None

    def deployments(self) -> tuple[tuple[str, str], ...]:
        """Every active (graph, platform) pair, sorted."""
        return tuple(
            sorted((self._g.nodes[s]["name"], self._g.nodes[t]["name"]) for s, t, _d in self.repo.edges(L.DEPLOYED_ON))
        )

    def history(self) -> tuple[tuple[str, str, float, float], ...]:
        """Every stopped deployment as (graph, platform, start, stop), in stop order."""
        rows = [
            (self._g.nodes[s]["name"], self._g.nodes[t]["name"], float(d["start"]), float(d["stop"]))
            for s, t, d in self.repo.edges(L.DEPLOYMENT_HISTORY)
        ]
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
            if source_label is not None and self._g.nodes[s].get("label") != source_label:
                continue
            if target_label is not None and self._g.nodes[t].get("label") != target_label:
                continue
            if any(d.get(k) != v for k, v in where.items()):
                continue
            yield s, t, d
