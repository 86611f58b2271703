"""Vectorised placement: requirement checking over thousands of platforms at once.

:func:`desmon.deployment.validity.check_validity` walks the platforms one by one in
Python. At fleet scale (thousands of platforms) that loop dominates, so this module
keeps the platform facts as *columns* -- numpy arrays with one row per platform --
and evaluates each requirement kind over all rows at once:

* ``up`` flags and ``preference`` values (the preference order is one stable argsort);
* per resource: capacities (NaN where a platform has none), background loads, and
  the deployed shares as a rows x slots matrix of amounts with the sharing graph's
  code beside each, so a Capacity check can leave out the graph being placed (and,
  for a tuple :data:`~desmon.deployment.validity.Placing`, the graphs it would free);
* per numeric property: values (NaN where missing); per attribute: integer codes of
  the value as written (its repr, what a reason shows), with the codes of each text
  (attributes compare as text: 1 and "1" match);
* per device kind and per (kind, vendor): counts of working devices.

**Exactness.** The answer is the same :class:`~desmon.deployment.validity.Validity`
the scalar path gives: same acceptable tuple in the same order, same rejected tuple
with equal :class:`~desmon.deployment.validity.Failure` objects. The masks replay the
scalar arithmetic operation by operation (a Capacity's free amount is
``capacity - (0 + share_1 + share_2 ...) - load`` in float64, as Python computes
it); rows whose numbers float64 could not hold exactly (integers beyond 2**40) make
the columns decline, and the caller takes the scalar path.

**Reasons.** The rejected rows' failures are built one requirement at a time over all
the rows the masks say fail it. Their texts come from the scalar
:func:`~desmon.deployment.validity.requirement_holds`, asked once per class of rows
whose facts shown in the text are equal in the columns (a Quantity's device count, a
Minimum's value by its bits, an Attribute's written value, which options of a
Selection hold) and shared with the rest of the class. A Capacity's text (free amount,
capacity, every share listed, load) differs on most rows, so it is formatted here from
the columns, each distinct number once with ``:g`` as the scalar formats it, and
checked against the scalar text on two rows of every batch: if either differs the
classes are used instead. Tests compare every text with the scalar one, row by row, on
generated fleets. A down platform's one failure comes from the scalar check too, once
for the on-demand and once for the other platforms. The failure tuples are then zipped
together per pattern of failing requirements. (Cold, every reason for one
specification over 10,000 platforms takes about 10-20 ms; ``python -m bench.bench_validity``.)

**Dispatch.** :class:`ColumnChecks` is the Checks port that uses the columns: a
caller that places over many platforms (the fleet) builds its Query port with it.
It takes the columns for :data:`VECTOR_MIN_PLATFORMS` platforms or more, and never
for a requirement kind the columns do not cover (a soft preference, say):
:func:`vector_validity` answers None and the scalar loop runs.

**Incremental upkeep.** Each column-backed Checks port keeps its last few column
stores (its ``columns``, a :class:`~desmon.deployment.memo.ColumnMemo`, which also
counts how its questions were answered). A new states tuple
equal to a kept one costs one tuple comparison; one that differs in a few rows
(what a repository event changes: one platform's up flag, load, devices or
deployments) rewrites only those rows (:meth:`PlatformColumns.sync`,
:meth:`PlatformColumns.update`). :class:`ChangeLogColumns` goes further and follows
a repository's change log, so no platform's facts are re-read unless a change
touched it.
"""

from __future__ import annotations

import sys
import threading
from itertools import repeat
from typing import Any, Callable, Iterable, Mapping, Sequence

import numpy as np

from desmon.deployment import validity as _validity
from desmon.deployment.columns import FactColumns, inexact
from desmon.deployment.memo import ColumnMemo
from desmon.deployment.ports import PlatformHandle
from desmon.errors import ModelError, QueryError
from desmon.model.requirements import CAPACITY_SLACK, Capacity, Option
from desmon.model.system import PlatformState
from desmon.repository import labels as _L
from desmon.repository.store import ADD_NODE

__all__ = [
    "VECTOR_MIN_PLATFORMS",
    "PlatformColumns",
    "ReasonMemo",
    "ChangeLogColumns",
    "vector_validity",
    "acceptable",
    "supported",
    "ColumnChecks",
    "PlatformMemoColumnChecks",
    "columns_for",
]

#: ``check_validity`` takes the columns from this many platforms on. Measured with
#: ``python -m bench.bench_validity --crossover`` (two runs): with the columns kept, the
#: fixed cost of the numpy calls, the batched failure texts included (about 85
#: microseconds a specification), breaks even with the loop at about 96 platforms; the
#: columns are 1.3x faster at 128 and 2x at 256.
VECTOR_MIN_PLATFORMS = 128

#: Failures kept for reuse per column store (a few hundred bytes each); beyond, the
#: least recently asked requirements lose theirs.
_REASONS_KEPT = 100_000

#: Python 3.12's ``sum`` adds floats with compensation; there, a Capacity sum of three
#: or more shares is left to the scalar code (row by row) so the verdicts stay equal.
_COMPENSATED_SUM = sys.version_info >= (3, 12)

_LOCK = threading.RLock()


def supported(requirements: Iterable[object]) -> bool:
    """True if every requirement is of a kind with columns (its class, the one defining its
    ``holds``, defines ``column_mask``: a subclass changing the semantics declines) whose
    numbers the columns hold exactly."""
    for req in requirements:
        if not getattr(type(req), "vectorised", False):
            return False
        if any(inexact(x) for x in req.column_numbers()):  # type: ignore[attr-defined]
            return False
    return True


#: A rejected platform's entry of ``Validity.rejected``: its name and its failures.
_Pair = tuple[str, tuple[Any, ...]]


class ReasonMemo:
    """(requirement, graph) -> row -> its Failure (the scalar text), kept until the row
    changes; beyond :data:`_REASONS_KEPT` failures the least recently asked requirements
    lose theirs."""

    def __init__(self) -> None:
        self._memos: dict[tuple[str, _validity.Placing], dict[int, _validity.Failure]] = {}
        self._size = 0  # failures held

    def of(self, req: object, graph: _validity.Placing) -> dict[int, _validity.Failure]:
        """Row -> the Failure of ``req`` for ``graph`` (to be filled: say how many with :meth:`added`)."""
        # repr: equal requirements may read differently (2 vs 2.0); only a Capacity's text
        # depends on the graph placed (whose shares it leaves out)
        key = (repr(req), graph if type(req).texts_read_graph else None)  # type: ignore[attr-defined]
        memo = self._memos.pop(key, None)
        if memo is None:
            memo = {}
            while self._size > _REASONS_KEPT and self._memos:  # least recently asked first
                self._size -= len(self._memos.pop(next(iter(self._memos))))
        self._memos[key] = memo  # (re)inserted last: the most recently asked
        return memo

    def added(self, k: int) -> None:
        """``k`` failures were put into a memo of :meth:`of`."""
        self._size += k

    def drop_row(self, i: int) -> None:
        """Forget row ``i``'s failures (its facts changed)."""
        for memo in self._memos.values():
            if memo.pop(i, None) is not None:
                self._size -= 1

    def clear(self) -> None:
        self._memos.clear()
        self._size = 0


class PlatformColumns:
    """The platform facts of one platform list as numpy columns (see the module doc).

    Build it from the states (``PlatformColumns(states)``), keep it current with
    :meth:`update` (rows by index) or :meth:`sync` (a whole new states tuple, only
    the changed rows rewritten), and ask :meth:`validity` or :meth:`acceptable`. The
    columns are its :class:`~desmon.deployment.columns.FactColumns`; the failures it
    explained, its :class:`ReasonMemo`.
    """

    def __init__(self, states: Sequence[PlatformState]) -> None:
        states = tuple(states)
        for i, s in enumerate(states):
            if not isinstance(s, PlatformState):
                raise ModelError(f"platform columns: item {i} = {s!r} is not a PlatformState: pass query.platform_states()")
        self.states: tuple[PlatformState, ...] = states
        self.n = len(states)
        self.facts = FactColumns(states)
        self.reasons = ReasonMemo()

    # -- keeping current ---------------------------------------------------------------------
    def update(self, changes: Mapping[int, PlatformState] | Iterable[tuple[int, PlatformState]]) -> int:
        """Rewrite the rows ``index -> new state`` (the same platform, new facts); returns
        how many rows changed. A state for another platform than the row's is refused."""
        items = changes.items() if isinstance(changes, Mapping) else changes
        states = list(self.states)
        count = 0
        for i, s in items:
            if type(i) is not int or not 0 <= i < self.n:
                raise QueryError(f"platform columns: row {i!r} is not an index in 0..{self.n - 1}: pass the platform's position")
            if not isinstance(s, PlatformState):
                raise ModelError(f"platform columns: row {i} = {s!r} is not a PlatformState: pass the platform's new state")
            if s.platform.name != self.facts.names[i]:
                raise QueryError(
                    f"platform columns: row {i} holds platform {self.facts.names[i]!r}, not {s.platform.name!r}: "
                    "build new columns for a changed platform list"
                )
            self._rewrite(i, s)
            states[i] = s
            count += 1
        self.states = tuple(states)
        return count

    def sync(self, states: tuple[PlatformState, ...]) -> bool:
        """Make the columns hold ``states`` by rewriting the rows that differ; False (and
        nothing changed) if ``states`` is another platform list (other names or length)."""
        old = self.states
        if old is states:
            return True
        if len(old) != len(states):
            return False
        if old == states:  # C-level; element identity first, so cheap for the same objects
            self.states = states
            return True
        names = self.facts.names
        changed = [(i, s) for i, (a, s) in enumerate(zip(old, states)) if a is not s and a != s]
        if any(s.platform.name != names[i] for i, s in changed):
            return False
        for i, s in changed:
            self._rewrite(i, s)
        self.states = states
        return True

    def _rewrite(self, i: int, s: PlatformState) -> None:
        self.reasons.drop_row(i)
        self.facts.rewrite(i, s)

    def forget_reasons(self) -> None:
        """Drop every memoised failure (memory; benchmarks timing a cold explanation)."""
        self.reasons.clear()

    # -- facts -------------------------------------------------------------------------------
    @property
    def exact(self) -> bool:
        """False if some row holds a number float64 cannot be trusted with (see module doc)."""
        return not self.facts.inexact_rows

    @property
    def nbytes(self) -> int:
        """Bytes held by the numpy columns (the names and code books not counted)."""
        return self.facts.nbytes

    def order(self) -> np.ndarray:
        """Row indices in preference order (higher ``preference`` first, then declaration order)."""
        return self.facts.order()

    # -- requirement kinds, vectorised -----------------------------------------------------------
    # Each kind's ``column_mask`` and ``column_keys`` (desmon.model.requirements) combine the
    # primitives below: columns of counts, properties, attribute tests and row keys.
    def holds(self, req: object, graph: _validity.Placing) -> np.ndarray:
        """Boolean row mask: where ``req`` holds for placing ``graph`` (up flags not applied)."""
        if not getattr(type(req), "vectorised", False):
            raise TypeError(f"platform columns cannot evaluate {req!r}: check supported() first")
        return req.column_mask(self, graph)  # type: ignore[attr-defined,no-any-return]

    def count(self, kind: str, vendor: str | None = None) -> np.ndarray:
        """Working devices of ``kind`` (of ``vendor``) per row."""
        col = self.facts.kinds.get(kind) if vendor is None else self.facts.vendors.get((kind, vendor))
        return col if col is not None else np.zeros(self.n, dtype=np.int32)

    _count = count

    def prop(self, name: str) -> np.ndarray | None:
        """The numeric property ``name`` per row (NaN where missing), or None if no row has it."""
        return self.facts.props.get(name)

    def none(self) -> np.ndarray:
        """A mask holding on no row."""
        return np.zeros(self.n, dtype=bool)

    def attr_is(self, name: str, value: object) -> np.ndarray:
        """Where attribute ``name`` equals ``value`` as text."""
        col = self.facts.attrs.get(name)
        codes = self.facts.attr_text.get(name, {}).get(str(value))
        if col is None or not codes:
            return np.zeros(self.n, dtype=bool)
        return col == codes[0] if len(codes) == 1 else np.isin(col, codes)

    _attr_is = attr_is

    def option(self, opt: Option) -> np.ndarray:
        """Where a Selection option is available."""
        if opt.attribute is not None:
            return self._attr_is(opt.attribute, opt.value)
        return self._count(opt.device_kind or "", opt.vendor) > 0

    _option = option

    def how_many(self, options: Iterable[Option]) -> np.ndarray:
        """How many of ``options`` are available per row."""
        have = np.zeros(self.n, dtype=np.int32)
        for opt in options:
            have += self._option(opt)
        return have

    def hosted_by(self, platforms: Iterable[str]) -> np.ndarray:
        """Where the row's platform is one of ``platforms``."""
        return np.isin(self.facts.names, tuple(platforms))

    def row_key(self, rows: np.ndarray) -> np.ndarray:
        """A text key for ``rows``: every row its own class."""
        return rows.astype(np.int64)

    def one_key(self, rows: np.ndarray) -> np.ndarray:
        """A text key for ``rows``: one class (the text is the same on every row)."""
        return np.zeros(len(rows), dtype=np.int8)

    def prop_key(self, name: str, rows: np.ndarray) -> np.ndarray:
        """A text key showing property ``name`` (by its bits: -0.0 and 0.0 differ; NaN: missing)."""
        col = self.facts.props.get(name)
        return col[rows].view(np.int64) if col is not None else np.zeros(len(rows), dtype=np.int64)

    def attr_key(self, name: str, rows: np.ndarray) -> np.ndarray:
        """A text key showing attribute ``name`` as written (codes of its repr; -1: missing)."""
        col = self.facts.attrs.get(name)
        return col[rows] if col is not None else np.zeros(len(rows), dtype=np.int32)

    def option_keys(self, options: Iterable[Option], rows: np.ndarray) -> np.ndarray:
        """A text key showing which of ``options`` hold (rows x options)."""
        return np.stack([self._option(o)[rows] for o in options], axis=1)

    def capacity(self, req: Capacity, graph: _validity.Placing) -> np.ndarray:
        """Where a Capacity holds, the free amount summed as :meth:`Capacity.holds` sums it."""
        cap = self.facts.caps.get(req.resource)
        if cap is None:
            return np.zeros(self.n, dtype=bool)
        used = np.zeros(self.n)
        sh = self.facts.shares.get(req.resource)
        excluded = self.facts.excluded(graph)
        counted = None
        if sh is not None:
            for j in range(sh.amounts.shape[1]):  # left to right, as Python's sum adds them
                col = sh.amounts[:, j]
                if excluded is not None:
                    col = np.where(np.isin(sh.graphs[:, j], excluded), 0.0, col)
                used = used + col
            if _COMPENSATED_SUM:
                counted = (sh.graphs >= 0) & ~np.isin(sh.graphs, excluded if excluded is not None else [])
        load = self.facts.loads.get(req.resource)
        free = cap - used - (load if load is not None else 0.0)
        ok = req.amount - free <= CAPACITY_SLACK * np.maximum(1.0, np.abs(cap))  # (Capacity.holds, elementwise: the same floats)
        if counted is not None:
            for i in np.flatnonzero(counted.sum(axis=1) >= 3).tolist():
                ok[i] = _validity.requirement_holds(req, self.states[i], graph) is None
        return ok

    # -- answers ---------------------------------------------------------------------------------
    def masks(self, requirements: Sequence[object], graph: _validity.Placing) -> np.ndarray:
        """requirements x rows: where each requirement holds (up flags not applied)."""
        if not requirements:
            return np.ones((0, self.n), dtype=bool)
        return np.stack([self.holds(r, graph) for r in requirements])

    def acceptable(self, requirements: Sequence[object], graph: _validity.Placing = None) -> tuple[str, ...]:
        """The acceptable platforms in preference order (``check_validity(...).acceptable``)."""
        good = self.facts.up.copy()
        for req in requirements:
            good &= self.holds(req, graph)
        order = self.order()
        return tuple(self.facts.names[order[good[order]]].tolist())

    def validity(self, requirements: Sequence[object], graph: _validity.Placing = None, *, reasons: bool = True) -> _validity.Validity:
        """What ``check_validity(requirements, self.states, graph, reasons=reasons)`` returns.

        Rejected rows get a failure for each requirement the masks say they fail (only
        the first one unless ``reasons``), with the scalar texts (see "Reasons" in the
        module doc).
        """
        reqs = tuple(requirements)
        ok = self.masks(reqs, graph)
        good = self.facts.up & ok.all(axis=0)
        order = self.order()
        in_order = good[order]
        acceptable = tuple(self.facts.names[order[in_order]].tolist())
        rows = order[~in_order]
        if not len(rows):
            return _validity.Validity(acceptable, ())
        return _validity.Validity(acceptable, _cols_rejected(self, reqs, ok[:, rows], rows, graph, reasons))

    def capacity_texts(self, req: Capacity, rows: np.ndarray, graph: _validity.Placing) -> list[str] | None:
        """A Capacity's reasons formatted from the columns (:func:`_cols_capacity_texts`), or None:
        on Python 3.12 (compensated sums) and where the format differs from the scalar one."""
        return None if _COMPENSATED_SUM else _cols_capacity_texts(self, req, rows, graph)

    def capacity_keys(self, req: Capacity, rows: np.ndarray, graph: _validity.Placing) -> np.ndarray:
        """Capacity text keys: the capacity, the load and each share the text lists (graph
        code and amount; a share of a graph left out is blanked)."""
        cap = self.facts.caps.get(req.resource)
        if cap is None:
            return np.zeros((len(rows), 1), dtype=np.int64)
        parts = [cap[rows].view(np.int64)[:, None]]
        load = self.facts.loads.get(req.resource)
        if load is not None:
            parts.append(load[rows].view(np.int64)[:, None])
        sh = self.facts.shares.get(req.resource)
        if sh is not None:
            graphs, amounts = sh.graphs[rows].astype(np.int64), sh.amounts[rows]
            excluded = self.facts.excluded(graph)
            if excluded is not None:
                left_out = np.isin(graphs, excluded)
                graphs[left_out] = -1
                amounts[left_out] = 0.0
            parts += [graphs, amounts.view(np.int64)]
        keys = np.concatenate(parts, axis=1)
        keys[np.isnan(cap[rows])] = 0  # "has no capacity": one text whatever the rest
        return keys


# -- incremental upkeep ----------------------------------------------------------------


def _cols_rejected(cols: "PlatformColumns", reqs: tuple, ok: np.ndarray, rows: np.ndarray, graph: _validity.Placing, reasons: bool) -> tuple[_Pair, ...]:
    """``(name, failures)`` of each rejected row, in the order of ``rows`` (``ok``: reqs x rows).

    Each failing (requirement, row) cell gets its Failure first, one requirement at a
    time; then the rows are grouped by which cells they fail, and each group's
    failure tuples are zipped together from those cells."""
    up = cols.facts.up[rows]
    failing = ~ok & up  # a down row fails only "platform up"
    if not reasons and len(reqs):  # the first failure only
        first = np.argmax(failing, axis=0)
        failing = np.zeros_like(failing)
        failing[first, np.arange(len(rows))] = up
    table = np.vstack([~up, failing])  # (1 + reqs) x rows: which failures each row has
    cells = [_cols_down_failures(cols, rows, ~up, graph)]
    cells += [_cols_failures(cols, req, rows, fails, graph) if fails.any() else None for req, fails in zip(reqs, failing)]
    _first, inv = _classes(table.T)
    out: list[Any] = [None] * len(rows)
    for pos in np.split(np.argsort(inv, kind="stable"), np.cumsum(np.bincount(inv))[:-1]):
        columns = [cells[k][pos].tolist() for k in np.flatnonzero(table[:, pos[0]]).tolist()]  # type: ignore[index]
        for p, fails in zip(pos.tolist(), zip(*columns)):
            out[p] = fails
    return tuple(zip(cols.facts.names[rows].tolist(), out))


def _cols_failures(cols: "PlatformColumns", req: Any, rows: np.ndarray, fails: np.ndarray, graph: _validity.Placing) -> np.ndarray:
    """Object array over ``rows``: the Failure of ``req`` where ``fails`` (None elsewhere),
    taken from the memo or made and kept there."""
    where = rows[fails]
    memo = cols.reasons.of(req, graph)
    got: list[Any] = list(map(memo.get, where.tolist())) if memo else [None] * len(where)
    missing = [j for j, f in enumerate(got) if f is None]
    if missing:
        new = where[missing] if len(missing) < len(where) else where
        names = cols.facts.names[new].tolist()
        made = list(map(_validity.Failure, names, repeat(req.describe()), _cols_texts(cols, req, new, graph)))
        memo.update(zip(new.tolist(), made))
        cols.reasons.added(len(made))
        if len(missing) == len(got):
            got = made
        else:
            for j, f in zip(missing, made):
                got[j] = f
    out = np.empty(len(rows), dtype=object)
    out[fails] = got
    return out


def _cols_down_failures(cols: "PlatformColumns", rows: np.ndarray, down: np.ndarray, graph: _validity.Placing) -> np.ndarray | None:
    """Object array over ``rows``: a down row's one failure, as the scalar check gives it
    (its text depends only on whether the platform is on demand)."""
    if not down.any():
        return None
    where = rows[down]
    scalar = _cols_shared(
        where, cols.facts.on_demand[where][:, None], lambda i: _validity.check_platform((), cols.states[i], graph, first_only=True)[0]
    )
    out = np.empty(len(rows), dtype=object)
    out[down] = [_validity.Failure(name, f.requirement, f.reason) for name, f in zip(cols.facts.names[where].tolist(), scalar)]
    return out


def _cols_texts(cols: "PlatformColumns", req: Any, rows: np.ndarray, graph: _validity.Placing) -> list[str]:
    """The reason ``req`` fails on each of ``rows`` (all failing): the kind's
    ``column_texts`` if it formats them (a Capacity's text, which differs on most rows:
    :meth:`capacity_texts`), else the scalar text, asked once per class of rows with
    equal :func:`_cols_text_keys`."""
    texts = req.column_texts(cols, rows, graph)
    if texts is not None:
        return texts  # type: ignore[no-any-return]
    return _cols_shared(rows, _cols_text_keys(cols, req, rows, graph), lambda i: _cols_reason(cols, req, i, graph))


def _cols_capacity_texts(cols: "PlatformColumns", req: Capacity, rows: np.ndarray, graph: _validity.Placing) -> list[str] | None:
    """Capacity reasons formatted from the columns, as the scalar formats them
    ("<free>[ MB] free (capacity <c>, used by <graph> <amount>, ..., load <l>)", every
    number with ``:g``; the free amount summed as :meth:`capacity` sums it). Checked
    against the scalar text on the first row and on a row listing the most shares:
    None (ask the scalar) if either differs."""
    cap = cols.facts.caps.get(req.resource)
    if cap is None:
        return None
    out = np.empty(len(rows), dtype=object)
    has = ~np.isnan(cap[rows])
    if not has.all():  # "has no <resource> capacity": one text
        out[~has] = _cols_reason(cols, req, int(rows[~has][0]), graph)
    where = rows[has]
    c = cap[where]
    load = cols.facts.loads.get(req.resource)
    l = load[where] if load is not None else np.zeros(len(where))
    used, shares, listed = np.zeros(len(where)), np.full(len(where), "", dtype=object), np.zeros(len(where), dtype=np.intp)
    sh = cols.facts.shares.get(req.resource)
    if sh is not None:
        graphs, amounts = sh.graphs[where], sh.amounts[where]
        excluded = cols.facts.excluded(graph)
        if excluded is not None:
            left_out = np.isin(graphs, excluded)
            graphs[left_out] = -1
            amounts[left_out] = 0.0
        used_by = np.array([f", used by {g} " for g in cols.facts.graph_code], dtype=object)  # by code
        for j in range(amounts.shape[1]):  # left to right, as Python's sum adds them
            used = used + amounts[:, j]
            on = graphs[:, j] >= 0
            if on.any():
                piece = np.full(len(where), "", dtype=object)
                piece[on] = used_by[graphs[on, j]] + _g(amounts[on, j])
                shares = shares + piece
                listed += on
    unit = " MB" if req.resource == "memory" else ""
    texts = _g(c - used - l) + f"{unit} free (capacity " + _g(c) + shares + ", load " + _g(l) + ")"
    for j in {0, int(np.argmax(listed))} if len(where) else ():
        if _validity.requirement_holds(req, cols.states[int(where[j])], graph) != texts[j]:
            return None
    out[has] = texts
    return out.tolist()  # type: ignore[no-any-return]


def _cols_reason(cols: "PlatformColumns", req: Any, i: int, graph: _validity.Placing) -> str:
    reason = _validity.requirement_holds(req, cols.states[i], graph)
    if reason is None:  # the masks and the scalar semantics disagree: a bug here
        raise AssertionError(f"placement columns: {req.describe()} fails on {cols.facts.names[i]} but the scalar check holds")
    return reason


def _cols_shared(rows: np.ndarray, keys: np.ndarray, ask: Callable[[int], Any]) -> list[Any]:
    """``ask(row)`` for each of ``rows``, asked only of the first row of each class of
    equal ``keys`` (rows x width) and shared with the rest of the class."""
    first, inv = _classes(keys)
    answers = np.empty(len(first), dtype=object)
    answers[:] = [ask(i) for i in rows[first].tolist()]
    return answers[inv].tolist()  # type: ignore[no-any-return]


def _cols_text_keys(cols: "PlatformColumns", req: Any, rows: np.ndarray, graph: _validity.Placing) -> np.ndarray:
    """rows x width integers such that rows with equal keys get byte-equal reason texts
    from the scalar semantics for ``req``: the facts each text shows, read from the
    columns (floats by their bits, so -0.0 and 0.0 differ; an int and the equal float
    print alike with ``:g``). Keys may split rows whose texts are equal, never join
    rows whose texts differ."""
    key = req.column_keys(cols, rows, graph)
    return key[:, None] if key.ndim == 1 else key  # type: ignore[no-any-return]


def _g(values: np.ndarray) -> np.ndarray:
    """Object array of ``f"{v:g}"`` for float64 ``values``, each distinct value formatted once
    (told apart by their bits: -0.0 prints "-0"). An int prints as the equal float does."""
    bits = np.ascontiguousarray(values, dtype=np.float64).view(np.int64)
    distinct, inv = np.unique(bits, return_inverse=True)
    texts = np.empty(len(distinct), dtype=object)
    texts[:] = [f"{v:g}" for v in distinct.view(np.float64).tolist()]
    return texts[inv.reshape(-1)]  # type: ignore[no-any-return]


def _classes(keys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows of ``keys`` (rows x width) grouped by equal bytes: the first row of each class
    and each row's class."""
    keys = np.ascontiguousarray(keys)
    if keys.shape[1] == 0:
        return np.zeros(1, dtype=np.intp), np.zeros(len(keys), dtype=np.intp)
    flat = keys.view(np.dtype((np.void, keys.dtype.itemsize * keys.shape[1]))).ravel()
    _u, first, inv = np.unique(flat, return_index=True, return_inverse=True)
    return first, inv.reshape(-1)


# -- the dispatch ----------------------------------------------------------------------------------
def columns_for(states: tuple[PlatformState, ...], memo: ColumnMemo | None = None) -> PlatformColumns:
    """Column store holding ``states``: one ``memo`` keeps (rewritten where rows changed),
    or a new one (kept by ``memo``; without a memo, nothing is kept)."""
    if memo is None:
        return PlatformColumns(states)
    with _LOCK:
        return memo.store_for(states, PlatformColumns)  # type: ignore[no-any-return]


def vector_validity(
    requirements: tuple, states: tuple[PlatformState, ...], graph: _validity.Placing, reasons: bool,
    min_platforms: int = VECTOR_MIN_PLATFORMS, memo: ColumnMemo | None = None,
) -> _validity.Validity | None:
    """The column answer of ``check_validity``, or None: fewer than ``min_platforms``
    platforms, or something the columns do not cover. ``memo`` keeps the column stores
    and counts the answers (:class:`~desmon.deployment.memo.ColumnMemo`)."""
    if len(states) < min_platforms:
        return None
    if memo is None:
        memo = ColumnMemo(kept=0)
    if not supported(requirements):
        memo.count("declined")
        return None
    with _LOCK:
        st = columns_for(states, memo)
        if not st.exact:
            memo.count("declined")
            return None
        memo.count("vector")
        return st.validity(requirements, graph, reasons=reasons)


class _ColumnsFirst:
    """``compute`` over numpy columns from ``min_platforms`` platforms on
    (:func:`vector_validity`), else (fewer platforms, or a requirement kind the columns do
    not cover) by the class's own one-platform-at-a-time ``_scalar``."""

    min_platforms: int
    #: the column stores it keeps and its counts of how questions were answered
    columns: ColumnMemo

    def compute(self, reqs: tuple, states: tuple[PlatformState, ...], graph: _validity.Placing, reasons: bool) -> _validity.Validity:
        if len(states) >= self.min_platforms:
            fast = vector_validity(reqs, states, graph, reasons, self.min_platforms, self.columns)
            if fast is not None:
                return fast
        return self._scalar(reqs, states, graph, reasons)

    def _scalar(self, reqs: tuple, states: tuple[PlatformState, ...], graph: _validity.Placing, reasons: bool) -> _validity.Validity:
        raise NotImplementedError


class ColumnChecks(_ColumnsFirst, _validity.ScalarChecks):
    """The Checks port for fleet scale: :data:`VECTOR_MIN_PLATFORMS` platforms or more
    (``min_platforms``) are checked over numpy columns (:func:`vector_validity`), fewer,
    or a requirement kind the columns do not cover, one platform at a time. Same
    answers as :class:`~desmon.deployment.validity.ScalarChecks`, and like it no answer
    is memoised (wrap it in a :class:`~desmon.deployment.memo.MemoChecks` for that); its
    ``columns`` keep the last column stores, rewritten row by row as platforms change."""

    def __init__(self, *, min_platforms: int = VECTOR_MIN_PLATFORMS) -> None:
        self.min_platforms = min_platforms
        self.columns = ColumnMemo()

    def _scalar(self, reqs: tuple, states: tuple[PlatformState, ...], graph: _validity.Placing, reasons: bool) -> _validity.Validity:
        return _validity.loop_validity(reqs, states, graph, reasons)


class PlatformMemoColumnChecks(_ColumnsFirst, _validity.PlatformMemoChecks):
    """:class:`ColumnChecks`' dispatch over :class:`~desmon.deployment.validity.PlatformMemoChecks`:
    :data:`VECTOR_MIN_PLATFORMS` platforms or more (``min_platforms``) over numpy
    columns, fewer one platform at a time with each platform's part memoised on the
    identities of its state and of the requirements (the fleet's robots: each asks
    about its few own PCs and edge servers, whose states are the same objects until
    they change; no whole answer is memoised). Same answers as
    :class:`~desmon.deployment.validity.ScalarChecks`."""

    def __init__(self, *, min_platforms: int = VECTOR_MIN_PLATFORMS, **memo: int) -> None:
        # memo: PlatformMemoChecks' own options (its size), with its defaults
        self.min_platforms = min_platforms
        self.columns = ColumnMemo()
        super().__init__(**memo)

    def _scalar(self, reqs: tuple, states: tuple[PlatformState, ...], graph: _validity.Placing, reasons: bool) -> _validity.Validity:
        return _validity.PlatformMemoChecks.compute(self, reqs, states, graph, reasons)


def acceptable(
    requirements: Iterable[object], states: Sequence[PlatformState], graph: _validity.Placing = None, memo: ColumnMemo | None = None
) -> tuple[str, ...]:
    """``check_validity(requirements, states, graph).acceptable`` without building the
    rejected platforms' failures: the fast question of a deployer that only places
    (``memo``: the column stores to keep and count with, as :func:`vector_validity`)."""
    reqs = tuple(requirements)
    states = tuple(states)
    if len(states) >= VECTOR_MIN_PLATFORMS and type(states[0]) is not PlatformHandle and supported(reqs):
        with _LOCK:
            st = columns_for(states, memo)
            if st.exact:
                if memo is not None:
                    memo.count("vector")
                return st.acceptable(reqs, graph)
    return _validity.check_validity(reqs, states, graph, reasons=False).acceptable  # type: ignore[arg-type]


# -- following a repository's change log ----------------------------------------------------------------
class ChangeLogColumns:
    """Columns kept current from a repository's change log (no re-read of untouched platforms).

    ``ChangeLogColumns(repo, query)`` subscribes to ``repo`` (a
    :class:`~desmon.repository.store.Repository`); each change that can alter a
    platform's facts -- the platform node's ``up`` or ``load``, a HAS_DEVICE edge, a
    DEPLOYED_ON edge added, removed or relabelled to history -- marks that platform.
    :meth:`states` re-reads only the marked platforms through ``query.platform_state``
    and :meth:`columns` rewrites only their rows. A new platform, or a change to a
    deployment node (its consumption), rebuilds everything on the next call.
    """

    def __init__(self, repo: Any, query: Any) -> None:
        self._query = query
        self._dirty: set[str] = set()
        self._rebuild = True
        self._states: list[PlatformState] = []
        self._index: dict[str, int] = {}
        self._columns: PlatformColumns | None = None
        self.reads = 0  #: platform states re-read so far (observability)
        self._sub = repo.subscribe(self._on_change)

    def close(self) -> None:
        """Stop following the change log."""
        self._sub.cancel()

    def _on_change(self, change: Any) -> None:
        L = _L
        if change.node is not None:
            if change.label == L.PLATFORM:
                if change.op == ADD_NODE:
                    self._rebuild = True
                else:
                    self._dirty.add(change.node.partition(":")[2])
            elif change.label == L.DEPLOYMENT:
                self._rebuild = True
            return
        if change.label == L.HAS_DEVICE:
            self._dirty.add(change.source.partition(":")[2])
        elif L.DEPLOYED_ON in (change.label, change.old_label):
            self._dirty.add(change.target.partition(":")[2])

    def states(self) -> tuple[PlatformState, ...]:
        """Every platform's facts in declaration order, re-reading only marked platforms."""
        if self._rebuild:
            fresh = self._query.platform_states()
            self.reads += len(fresh)
            self._states = list(fresh)
            self._index = {s.platform.name: i for i, s in enumerate(fresh)}
            self._dirty.clear()
            self._rebuild = False
            self._columns = None
        changes = {}
        for name in sorted(self._dirty):
            i = self._index[name]
            self._states[i] = changes[i] = self._query.platform_state(name)
            self.reads += 1
        self._dirty.clear()
        if changes and self._columns is not None:
            self._columns.update(changes)
        return tuple(self._states)

    def columns(self) -> PlatformColumns:
        """The column store of :meth:`states`, its changed rows rewritten."""
        states = self.states()
        if self._columns is None:
            self._columns = PlatformColumns(states)
        return self._columns

