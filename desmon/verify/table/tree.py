"""The table engine's decision trees: what a reaction did, per answer to what it observed.

One tree per root (system part, global digit, stimulus, failed-start prefix). A node
is an observation (a requirement check over some platforms), with one branch per
answer code; a leaf is what the reaction did (next system part, start outcomes,
deployer branches, an instantaneous violation) or, for an invariants root, which
invariants the state violates. :meth:`DecisionTrees.walk` resolves a whole batch of
units at once with numpy, calling back to record a real run where the trees have no
branch yet; :meth:`DecisionTrees.insert` adds a recorded run's path.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from desmon.errors import NondeterminismError, TableUnsupported
from desmon.verify.table.tables import AnswerTables, Grow, Interned

__all__ = ["DecisionTrees"]


class DecisionTrees:
    """The decision trees of one search over ``tables``; ``go_on()`` raises when the search must stop."""

    def __init__(self, tables: AnswerTables, platforms: int, go_on: Callable[[], None]) -> None:
        self.tables, self.go_on = tables, go_on
        P = platforms
        self.roots: dict[int, int] = {}
        self.node_leaf = Grow((1024,), -2)  # -2 open, -1 check node, >= 0 leaf id
        self.node_desc: list[tuple | None] = []
        self.node_base = Grow((1024, P))
        self.node_plat = Grow((1024, P))
        self.node_mult = Grow((1024, P))
        self.node_len = Grow((1024,))
        self.edges: dict[int, int] = {}
        self._ekeys = np.zeros(0, dtype=np.int64)
        self._echild = np.zeros(0, dtype=np.int64)
        self._new_edges: dict[int, int] = {}  # edges added since the arrays were last merged
        self.leaves = Interned()
        self.leaf_sys: list[int] = []  # a reaction leaf's next system part (-1: an invariants leaf)
        self.leaf_inst: list[bool] = []  # a reaction leaf with an instantaneous violation
        self.width = 1

    def leaf(self, value: tuple) -> int:
        """The number of leaf ``value``: ("r", system, outcomes, fails, branch names, instant) or ("v", violated)."""
        n = len(self.leaves)
        i = self.leaves(value)
        if i == n:  # a new leaf
            self.leaf_sys.append(value[1] if value[0] == "r" else -1)
            self.leaf_inst.append(value[0] == "r" and value[5] is not None)
        return i

    def _node(self) -> int:
        self.node_desc.append(None)
        self.node_base.append(0)
        self.node_plat.append(0)
        self.node_mult.append(0)
        self.node_len.append(1)
        n = self.node_leaf.append(-2)
        if n >= 1 << 22:
            raise TableUnsupported("table engine: more than 4 million decision nodes; run with --engine direct")
        return n

    def insert(self, root: int, obs: list[tuple[tuple, int]], leaf: int) -> None:
        node = self.roots.get(root)
        if node is None:
            node = self.roots[root] = self._node()
        for desc, code in obs:
            state = self.node_leaf.a[node]
            if state == -2:
                mode, table, first_only, parts = desc
                self.node_leaf.a[node] = -1
                self.node_desc[node] = desc
                mult = 1
                for j, (p, dep) in enumerate(parts):
                    off, radix = self.tables.block(mode, table, first_only, p, dep)
                    self.node_base.a[node, j] = off
                    self.node_plat.a[node, j] = p
                    self.node_mult.a[node, j] = mult
                    mult *= radix
                self.node_len.a[node] = len(parts)
                if mult > 1 << 40:
                    raise TableUnsupported("table engine: a requirement check with too many distinct answers; run with --engine direct")
                self.width = max(self.width, len(parts))
            elif state != -1 or self.node_desc[node] != desc:
                raise NondeterminismError(
                    "the deployment core checked different requirements on a state with the same readings: "
                    "it is not a function of what it reads through its ports"
                )
            ek = (node << 40) | code
            child = self.edges.get(ek)
            if child is None:
                child = self.edges[ek] = self._new_edges[ek] = self._node()
            node = child
        state = self.node_leaf.a[node]
        if state == -2:
            self.node_leaf.a[node] = leaf
        elif state != leaf:
            raise NondeterminismError(
                "the deployment core reacted differently to states with the same readings: "
                "it is not a function of what it reads through its ports"
            )

    def walk(self, roots: np.ndarray, rows: np.ndarray, loc: np.ndarray, record: Callable[[int], None]) -> np.ndarray:
        """Leaf ids for units with root keys ``roots`` and platform digits ``loc[rows]``;
        ``record(unit)`` runs the real core for a unit whose answers leave the trees."""
        go_on = self.go_on  # the budget, between two recorded runs and two rounds
        uk, first, inv = np.unique(roots, return_index=True, return_inverse=True)
        top = np.empty(len(uk), dtype=np.int64)
        for i, k in enumerate(uk.tolist()):
            n = self.roots.get(k)
            if n is None:
                go_on()
                record(int(first[i]))
                n = self.roots[k]
            top[i] = n
        node = top[inv]
        active = np.flatnonzero(self.node_leaf.a[node] < 0)
        while active.size:
            go_on()
            nd = node[active]
            r = rows[active]
            ok = self.tables.ok.a
            base, plat, mult = self.node_base.a, self.node_plat.a, self.node_mult.a
            # the answer code of each unit's check: most checks ask about one platform,
            # so position j is computed only for the units whose check has more
            code = ok[base[nd, 0] + loc[r, plat[nd, 0]]] * mult[nd, 0]
            if self.width > 1:
                wide = np.flatnonzero(self.node_len.a[nd] > 1)
                for j in range(1, self.width):
                    if not wide.size:
                        break
                    w = nd[wide]
                    code[wide] += ok[base[w, j] + loc[r[wide], plat[w, j]]] * mult[w, j]
                    wide = wide[self.node_len.a[w] > j + 1]
            ek = (nd << 40) | code
            child = self._lookup(ek)
            missed = np.flatnonzero(child < 0)
            if missed.size:
                _again, firsts = np.unique(ek[missed], return_index=True)
                for m in np.sort(firsts):
                    go_on()
                    record(int(active[missed[m]]))
                child[missed] = self._lookup(ek[missed])
                if (child[missed] < 0).any():
                    raise TableUnsupported(  # pragma: no cover - an unobserved rewrite of facts, or a bug in the engine
                        "table engine: a per-platform answer disagrees with the real requirement check; run with --engine direct"
                    )
            node[active] = child
            active = active[self.node_leaf.a[child] < 0]
        return self.node_leaf.a[node]

    def _lookup(self, ek: np.ndarray) -> np.ndarray:
        """The child node of each (node << 40 | answer code), -1 where the trees have none yet."""
        if self._new_edges:
            nk = np.array(sorted(self._new_edges), dtype=np.int64)
            nv = np.array([self._new_edges[k] for k in nk.tolist()], dtype=np.int64)
            at = np.searchsorted(self._ekeys, nk)
            self._ekeys = np.insert(self._ekeys, at, nk)
            self._echild = np.insert(self._echild, at, nv)
            self._new_edges = {}
        out = np.full(len(ek), -1, dtype=np.int64)
        if len(self._ekeys):
            pos = np.searchsorted(self._ekeys, ek)
            np.minimum(pos, len(self._ekeys) - 1, out=pos)
            hit = self._ekeys[pos] == ek
            out[hit] = self._echild[pos[hit]]
        return out
