"""A Query port over the live networkx repository with an index of DEPLOYED_ON edges.

:class:`desmon.repository.query.RepositoryQuery` finds active deployments by scanning
every in-edge of a platform, DEPLOYMENT_HISTORY edges included, so its cost grows with
the length of the run (quadratic over a robot day). :class:`IndexedQuery` answers the
same queries on the same repository, but keeps the DEPLOYED_ON edges indexed from the
repository's own change notifications (Notify). ``tests/test_sim_query.py`` checks it
answers exactly as :class:`RepositoryQuery` does.
"""

from __future__ import annotations

from typing import Any

from desmon.repository import labels as L
from desmon.repository.query import RepositoryQuery
from desmon.repository.store import ADD_EDGE, RELABEL_EDGE, REMOVE_EDGE, Repository

__all__ = ["IndexedQuery"]


class IndexedQuery(RepositoryQuery):
    def __init__(self, repo: Repository) -> None:
        super().__init__(repo)
        self._into: dict[str, dict[str, None]] = {}
        self._from: dict[str, dict[str, None]] = {}
        for s, t, _d in repo.edges(L.DEPLOYED_ON):
            self._add(s, t)
        repo.subscribe(self._on_change, ops=(ADD_EDGE, REMOVE_EDGE, RELABEL_EDGE), labels=(L.DEPLOYED_ON,))

    def _add(self, s: str, t: str) -> None:
        self._into.setdefault(t, {})[s] = None
        self._from.setdefault(s, {})[t] = None

    def _on_change(self, c: Any) -> None:
        if c.op == ADD_EDGE and c.label == L.DEPLOYED_ON:
            self._add(c.source, c.target)
        elif (c.op == RELABEL_EDGE and c.old_label == L.DEPLOYED_ON) or (c.op == REMOVE_EDGE and c.label == L.DEPLOYED_ON):
            self._into.get(c.target, {}).pop(c.source, None)
            self._from.get(c.source, {}).pop(c.target, None)

    def _in(self, nid: str, label: str) -> list[str]:
        if label == L.DEPLOYED_ON:
            return list(self._into.get(nid, ()))
        return super()._in(nid, label)

    def _out(self, nid: str, label: str) -> list[str]:
        if label == L.DEPLOYED_ON:
            return list(self._from.get(nid, ()))
        return super()._out(nid, label)
