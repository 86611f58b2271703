"""The table engine's decision trees: what a reaction did, per answer to what it observed.

One tree per root (system part, global digit, stimulus, failed-start prefix), a node
per observation and a leaf per outcome (docs/findings.md, "How the table engine
works"); for an invariants root a leaf is which invariants the state violates.
:meth:`DecisionTrees.walk` resolves a batch of units with numpy, calling back to record
a real run where the trees have no branch yet; :meth:`DecisionTrees.insert` adds its path.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from desmon.errors import ObservationConflict, TableUnsupported
from desmon.verify.arrays import Grow, Interned, IntTable
from desmon.verify.table.tables import AnswerTables

__all__ = ["DecisionTrees", "DENSE_ANSWERS", "SMALL_DIGITS"]

#: a check node with at most this many answer codes keeps its children in an array
DENSE_ANSWERS = 64
#: a platform with at most this many digits has its shortcuts recomputed in plain Python
SMALL_DIGITS = 32
#: walk codes (:meth:`_Walk.walk`): a one-platform check is ``digit_base << code_bits | platform``
#: (below WIDE), another check ``WIDE | node``, a leaf node ``LEAF | leaf``
WIDE, LEAF = 1 << 60, 1 << 61


class _Walk:
    """The walk half of :class:`DecisionTrees`: the leaf of each unit of a batch, a round
    of array operations per level of the trees (it reads the arrays the inserts keep)."""

    def _root_nodes(self, roots: np.ndarray, record: Callable[[int], None]) -> np.ndarray:
        """The root node of each unit, recording a run for each root met for the first time
        (in order of root key, with its first unit)."""
        self._add_new_roots()
        node = self.root_nodes.get(roots)
        missing = np.flatnonzero(node < 0)
        if missing.size:
            _uk, first = np.unique(roots[missing], return_index=True)
            for u in missing[first].tolist():
                self.go_on()
                record(u)
            self._add_new_roots()
            node[missing] = self.root_nodes.get(roots[missing])
        return node

    def _add_new_roots(self) -> None:
        """Enter the roots the inserts made since the last walk in the roots' hash table."""
        if self._new_roots:
            self.root_nodes.add(np.fromiter(self._new_roots, dtype=np.int64), np.fromiter(self._new_roots.values(), dtype=np.int64))
            self._new_roots = {}

    def walk(self, roots: np.ndarray, rows: np.ndarray, loc: np.ndarray, record: Callable[[int], None]) -> np.ndarray:
        """Leaf ids for units with root keys ``roots`` and platform digits ``loc[rows]``;
        ``record(unit)`` runs the real core for a unit whose answers leave the trees. Each
        unit moves by its walk code (docs/design.md), one step per check (:meth:`_step`)."""
        go_on = self.go_on  # the budget, between two recorded runs and two rounds
        node = self._root_nodes(roots, record)  # (it may record runs: the arrays below grow)
        out = np.take(self.node_code.a, node)
        P = loc.shape[1]
        flat_loc = loc.ravel()
        # (np.take and index arrays, not boolean masks: several times faster on these sizes)
        idx = np.flatnonzero(out < LEAF)  # the units still at a check node
        cur, rp = np.take(out, idx), np.take(rows, idx) * P
        while idx.size:
            go_on()
            child = self._step(cur, rp, flat_loc)
            if child.min() < 0:
                self._record_missed(child, idx, cur, rp, flat_loc, record)
            out[idx] = child  # final for the units at a leaf, overwritten later for the others
            keep = np.flatnonzero(child < LEAF)
            if len(keep) < len(child):
                idx, cur, rp = idx.take(keep), child.take(keep), rp.take(keep)
            else:
                cur = child
        out -= LEAF
        return out

    def _record_missed(self, child: np.ndarray, idx: np.ndarray, cur: np.ndarray, rp: np.ndarray, flat_loc: np.ndarray,
                       record: Callable[[int], None]) -> None:
        """Record a run for each distinct missing branch (``child`` -1), with its first unit,
        and fill in the children the runs added."""
        missed = np.flatnonzero(child < 0)
        c = cur[missed]
        nd = np.where(c >= WIDE, c - WIDE, np.take(self.digit_node.a, np.where(c >= WIDE, 0, c >> self.code_bits)))
        _again, firsts = np.unique(self._edge_keys(nd, rp[missed], flat_loc), return_index=True)
        for m in np.sort(firsts).tolist():
            self.go_on()
            record(int(idx[missed[m]]))
        child[missed] = self._step(c, rp[missed], flat_loc)
        if (child[missed] < 0).any():
            raise TableUnsupported(  # pragma: no cover - an unobserved rewrite of facts, or a bug in the engine
                "table engine: a per-platform answer disagrees with the real requirement check; run with --engine direct"
            )

    def _step(self, cur: np.ndarray, rp: np.ndarray, flat_loc: np.ndarray) -> np.ndarray:
        """The walk code of the child of each check with walk code ``cur`` for its unit's
        answer (-1: no branch yet): from its platform's digit at a one-platform check (and
        on past the checks of the same platform), else from the answer code."""
        bits, mask = self.code_bits, (1 << self.code_bits) - 1
        if self.width == 1 or cur.max() < WIDE:  # (width 1: every check is about one platform)
            at = cur & mask
            at += rp
            digit = flat_loc.take(at)
            np.right_shift(cur, bits, out=at)
            at += digit
            return self.jump_code.a.take(at)
        child = np.empty_like(cur)
        one, other = np.flatnonzero(cur < WIDE), np.flatnonzero(cur >= WIDE)
        c = cur[one]
        child[one] = np.take(self.jump_code.a, (c >> bits) + np.take(flat_loc, rp[one] + (c & mask)))
        kids = self._children(cur[other] - WIDE, rp[other], flat_loc)
        child[other] = np.where(kids >= 0, np.take(self.node_code.a, kids), -1)
        return child

    def _codes(self, nd: np.ndarray, rp: np.ndarray, flat_loc: np.ndarray) -> np.ndarray:
        """The answer code of each unit's check at node ``nd`` (``rp``: its row of platform
        digits times the row's width): most checks ask about one platform, so position j
        is computed only for the units whose check has more."""
        ok = self.tables.ok.a
        base, plat, mult = self.node_base.a, self.node_plat.a, self.node_mult.a
        code = ok[base[nd, 0] + flat_loc[rp + plat[nd, 0]]]
        if self.width > 1:
            wide = np.flatnonzero(self.node_len.a[nd] > 1)
            for j in range(1, self.width):
                if not wide.size:
                    break
                w = nd[wide]
                code[wide] += ok[base[w, j] + flat_loc[rp[wide] + plat[w, j]]] * mult[w, j]
                wide = wide[self.node_len.a[w] > j + 1]
        return code

    def _edge_keys(self, nd: np.ndarray, rp: np.ndarray, flat_loc: np.ndarray) -> np.ndarray:
        return (nd << 40) | self._codes(nd, rp, flat_loc)

    def _children(self, nd: np.ndarray, rp: np.ndarray, flat_loc: np.ndarray) -> np.ndarray:
        """The child of each check node ``nd`` for its unit's answer, -1 where the trees have none yet."""
        code = self._codes(nd, rp, flat_loc)
        kb = self.kid_base.a[nd]
        wide = np.flatnonzero(kb < 0)
        if not wide.size:
            return self.kids.a[kb + code]
        at = kb + code
        at[wide] = 0
        child = self.kids.a[at]
        child[wide] = self.wide_edges.get((nd[wide] << 40) | code[wide])
        return child


class DecisionTrees(_Walk):
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
        self.node_len = Grow((1024,), 1)
        self.edges: dict[int, int] = {}
        # a check node's children: with at most DENSE_ANSWERS answer codes, kids[kid_base[node] + code]
        # (-1: no branch yet); beyond, in the hash table of (node << 40 | code) edges
        self.kid_base = Grow((1024,), -1)
        # a check node about one platform: its child per digit of that platform (the answer
        # table and the answer's branch in one), digit_kids[digit_base[node] + digit]
        self.digit_base = Grow((1024,), -1)
        self.digit_kids = Grow((1024,), -1, np.int32)
        # the walk's shortcut beside digit_kids: where the child for a digit checks the same
        # platform again and has a branch for that digit, the node that branch leads to
        # (repeatedly); else the child itself (:meth:`_rejump`)
        self.digit_jump = Grow((1024,), -1, np.int32)
        # the walk's view of the same shortcuts: digit_jump's targets as walk codes
        # (:meth:`_code`), so that a step reads one array; kept by :meth:`_recode`
        self.jump_code = Grow((1024,), -1)
        self.node_code = Grow((1024,), -1)  # each node's walk code (-1: open)
        self.digit_node = Grow((1024,), -1, np.int32)  # the node whose digit table starts at an offset
        self.code_bits = max(1, (platforms - 1).bit_length())  # the low bits of a check's code: its platform
        self.small_digits = SMALL_DIGITS
        self.node_p0 = Grow((1024,))
        self.kids = Grow((1024,), -1)
        self.wide_edges = IntTable()
        self._new_roots: dict[int, int] = {}
        self.root_nodes = IntTable()
        self.leaves = Interned()
        self.leaf_sys: list[int] = []  # a reaction leaf's next system part (-1: an invariants leaf)
        self.leaf_inst: list[bool] = []  # a reaction leaf that broke an invariant inside its reaction
        self.width = 1
        self._per_node = (self.node_leaf, self.kid_base, self.digit_base, self.node_p0, self.node_base, self.node_plat,
                          self.node_mult, self.node_code, self.node_len)

    def leaf(self, value: tuple) -> int:
        """The number of leaf ``value``: ("r", system, outcomes, fails, branch names, the invariants
        it broke inside its reaction) or ("v", violated)."""
        n = len(self.leaves)
        i = self.leaves(value)
        if i == n:  # a new leaf
            self.leaf_sys.append(value[1] if value[0] == "r" else -1)
            self.leaf_inst.append(value[0] == "r" and bool(value[5]))
        return i

    def _node(self) -> int:
        n = self.node_leaf.n
        for g in self._per_node:  # (their fill values)
            g.extend(1)
        self.node_desc.append(None)
        if n >= 1 << 22:
            raise TableUnsupported("table engine: more than 4 million decision nodes; run with --engine direct")
        return n

    def _open(self, node: int, desc: tuple) -> None:
        """Make open node ``node`` the check ``desc`` (mode, table, first_only, parts)."""
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
        p0 = self.node_p0.a[node] = parts[0][0]
        if len(parts) == 1:
            r = self.tables.env.R[p0]
            db = self.digit_base.a[node] = self.digit_kids.extend(r)
            for g in (self.digit_jump, self.jump_code, self.digit_node):
                g.extend(r)
            self.digit_node.a[db] = node
            self.node_code.a[node] = db << self.code_bits | p0
        else:
            self.node_code.a[node] = WIDE | node
        if mult <= DENSE_ANSWERS:
            self.kid_base.a[node] = self.kids.extend(mult)
        self.width = max(self.width, len(parts))

    def insert(self, root: int, obs: list[tuple[tuple, int]], leaf: int) -> None:
        node = self.roots.get(root)
        if node is None:
            node = self.roots[root] = self._new_roots[root] = self._node()
        path: list[tuple[int, bool]] = []  # (node, whether this insert changed its branches)
        made = None  # (parent, code) of a branch this insert made to ``node``
        for desc, code in obs:
            state = self.node_leaf.a[node]
            if state == -2:
                self._open(node, desc)
            elif state != -1 or self.node_desc[node] != desc:
                raise ObservationConflict(
                    "the deployment core checked different requirements on a state with the same readings: "
                    "it is not a function of what it reads through its ports"
                )
            if made is not None:  # (now that its walk code is known)
                self._digit_branch(made[0], made[1], node)
            ek = (node << 40) | code
            child = self.edges.get(ek)
            path.append((node, child is None))
            made = None
            if child is None:
                child = self.edges[ek] = self._node()
                made = (node, code)
                kb = int(self.kid_base.a[node])
                if kb >= 0:
                    self.kids.a[kb + code] = child
                else:
                    self.wide_edges.add(np.array([ek], dtype=np.int64), np.array([child], dtype=np.int64))
            node = child
        state = self.node_leaf.a[node]
        if state == -2:
            self.node_leaf.a[node] = leaf
            self.node_code.a[node] = LEAF | leaf
        elif state != leaf:
            raise ObservationConflict(
                "the deployment core reacted differently to states with the same readings: "
                "it is not a function of what it reads through its ports"
            )
        if made is not None:
            self._digit_branch(made[0], made[1], node)
        self._rejump_path(path)

    def _rejump_path(self, path: list[tuple[int, bool]]) -> None:
        """Bring the shortcuts (``digit_jump``, ``jump_code``: docs/design.md) of an insert's
        path up to date, deepest first: a node's can change only where its child on the
        path checks the same platform and that child's branches or shortcuts changed (a
        new branch's shortcut is its child, set by :meth:`_digit_branch`)."""
        below = False  # the shortcuts of the node below on the path changed
        base, p0 = self.digit_base.a, self.node_p0.a
        for i in range(len(path) - 1, -1, -1):
            node, new = path[i]
            if below:
                child = path[i + 1][0]
                db, cb = int(base[node]), int(base[child])
                if db >= 0 and cb >= 0 and int(p0[node]) == int(p0[child]):
                    self._rejump(node, child)
                    new = True
            below = new

    def _rejump(self, node: int, child: int) -> None:
        """Recompute the shortcuts of one-platform check ``node`` for the digits whose branch
        is ``child``, a check of the same platform, from ``child``'s (current) ones."""
        db, cb = int(self.digit_base.a[node]), int(self.digit_base.a[child])
        r = self.tables.env.R[int(self.node_p0.a[node])]
        kids_of, jump, jc, own = self.digit_kids.a, self.digit_jump.a, self.jump_code.a, int(self.node_code.a[child])
        if r <= self.small_digits:  # a few digits: plain Python is several times faster than numpy calls
            for d, kid in enumerate(kids_of[db: db + r].tolist(), db):
                if kid == child:
                    on = kids_of[cb - db + d] >= 0
                    jump[d] = jump[cb - db + d] if on else child
                    jc[d] = jc[cb - db + d] if on else own
            return
        digits = np.flatnonzero(kids_of[db: db + r] == child)
        on = kids_of[cb + digits] >= 0
        jump[db + digits] = np.where(on, jump[cb + digits], child)
        jc[db + digits] = np.where(on, jc[cb + digits], own)

    def _digit_branch(self, node: int, code: int, child: int) -> None:
        """Enter ``child`` (its walk code made) for every digit of a one-platform node that answers ``code``."""
        db = int(self.digit_base.a[node])
        if db >= 0:
            base, own = int(self.node_base.a[node, 0]), int(self.node_code.a[child])
            kids, jump, jc = self.digit_kids.a, self.digit_jump.a, self.jump_code.a
            for d, c in enumerate(self.tables.ok.a[base: base + self.tables.env.R[int(self.node_p0.a[node])]].tolist(), db):
                if c == code:
                    kids[d] = jump[d] = child  # (a new node: nothing to skip yet)
                    jc[d] = own
