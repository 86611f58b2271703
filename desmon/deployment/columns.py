"""The platform facts of one platform list as numpy columns, one row per platform.

What :mod:`desmon.deployment.placement` evaluates requirement kinds over (its module
doc says what the columns hold and why): ``up`` flags and preferences; per resource the
capacities, background loads and deployed shares (rows x slots, with the sharing
graph's code beside each amount); per numeric property its values; per attribute the
codes of its values; per device kind and per (kind, vendor) the working devices. A row
is rewritten in place when its platform's facts change.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from desmon.model.kinds import Placing
from desmon.model.state import PlatformState

__all__ = ["FactColumns", "Shares", "inexact", "EXACT_INT"]

#: Integers beyond this do not survive float64 sums exactly: such rows decline.
EXACT_INT = 2**40


def inexact(x: object) -> bool:
    """Whether ``x`` is an integer float64 cannot be trusted with (beyond :data:`EXACT_INT`)."""
    return type(x) is int and abs(x) > EXACT_INT  # type: ignore[arg-type]


@dataclass(slots=True)
class Shares:
    """One resource's deployed shares: rows x slots amounts and the graph codes (-1: empty)."""

    amounts: np.ndarray
    graphs: np.ndarray


class FactColumns:
    """The facts of one platform list as numpy columns, each row rewritten as its platform
    changes (:meth:`rewrite`). :class:`~desmon.deployment.placement.PlatformColumns` and
    its reason texts read the columns and code books below; only this class writes them."""

    def __init__(self, states: tuple[PlatformState, ...]) -> None:
        n = self.n = len(states)
        self.names = np.array([s.platform.name for s in states], dtype=object)
        #: graph -> its code in the share columns
        self.graph_code: dict[str, int] = {}
        #: attribute -> repr(value) -> code (the reason text shows the repr), and
        #: attribute -> str(value) -> its codes (attributes compare as text: 1 and "1" match)
        self.attr_code: dict[str, dict[str, int]] = {}
        self.attr_text: dict[str, dict[str, list[int]]] = {}
        #: rows holding a number float64 cannot be trusted with
        self.inexact_rows: set[int] = set()
        self._order: np.ndarray | None = None
        self.up = np.fromiter((s.up for s in states), dtype=bool, count=n)
        self.on_demand = np.fromiter((s.platform.on_demand for s in states), dtype=bool, count=n)
        self.pref = np.fromiter((s.platform.preference for s in states), dtype=np.float64, count=n)
        caps: dict[str, dict[int, float]] = {}
        loads: dict[str, dict[int, float]] = {}
        props: dict[str, dict[int, float]] = {}
        attrs: dict[str, dict[int, int]] = {}
        kinds: dict[str, dict[int, int]] = {}
        vendors: dict[tuple[str, str], dict[int, int]] = {}
        shares: dict[str, dict[int, list[tuple[int, float]]]] = {}
        for i, s in enumerate(states):
            facts = self._facts(i, s)
            for table, row in zip((caps, loads, props, attrs, kinds, vendors, shares), facts):
                for key, value in row.items():
                    table.setdefault(key, {})[i] = value  # type: ignore[index]
        self.caps = {k: self._column(v, np.nan, np.float64) for k, v in caps.items()}
        self.loads = {k: self._column(v, 0.0, np.float64) for k, v in loads.items()}
        self.props = {k: self._column(v, np.nan, np.float64) for k, v in props.items()}
        self.attrs = {k: self._column(v, -1, np.int32) for k, v in attrs.items()}
        self.kinds = {k: self._column(v, 0, np.int32) for k, v in kinds.items()}
        self.vendors = {k: self._column(v, 0, np.int32) for k, v in vendors.items()}
        self.shares = {k: self._share_matrix(v) for k, v in shares.items()}

    @property
    def nbytes(self) -> int:
        """Bytes held by the numpy columns (the names and code books not counted)."""
        arrays = [self.up, self.on_demand, self.pref, *self.caps.values(), *self.loads.values(), *self.props.values()]
        arrays += [*self.attrs.values(), *self.kinds.values(), *self.vendors.values()]
        arrays += [a for sh in self.shares.values() for a in (sh.amounts, sh.graphs)]
        return sum(a.nbytes for a in arrays)

    def order(self) -> np.ndarray:
        """Row indices in preference order (higher ``preference`` first, then declaration order)."""
        if self._order is None:
            self._order = np.argsort(-self.pref, kind="stable")
        return self._order

    def excluded(self, graph: Placing) -> np.ndarray | None:
        """The codes of the graphs ``graph`` leaves out of the shares (None: none deployed)."""
        names = () if graph is None else (graph,) if type(graph) is str else graph
        codes = [self.graph_code[g] for g in names if g in self.graph_code]  # type: ignore[union-attr]
        return np.array(codes, dtype=np.int32) if codes else None

    def rewrite(self, i: int, s: PlatformState) -> None:
        """Row ``i`` holds ``s`` (the same platform, new facts)."""
        self.up[i] = s.up
        self.on_demand[i] = s.platform.on_demand
        if self.pref[i] != s.platform.preference:
            self.pref[i] = s.platform.preference
            self._order = None
        caps, loads, props, attrs, kinds, vendors, shares = self._facts(i, s)
        for table, row, default, dtype in (
            (self.caps, caps, np.nan, np.float64),
            (self.loads, loads, 0.0, np.float64),
            (self.props, props, np.nan, np.float64),
            (self.attrs, attrs, -1, np.int32),
            (self.kinds, kinds, 0, np.int32),
            (self.vendors, vendors, 0, np.int32),
        ):
            for key, col in table.items():
                col[i] = row.get(key, default)
            for key in row.keys() - table.keys():
                table[key] = col = np.full(self.n, default, dtype=dtype)
                col[i] = row[key]
        for res, sh in self.shares.items():
            sh.amounts[i] = 0.0
            sh.graphs[i] = -1
        for res, entries in shares.items():
            sh = self.shares.get(res)
            if sh is None or sh.amounts.shape[1] < len(entries):
                sh = self._widen(res, len(entries))
            for j, (code, amount) in enumerate(entries):
                sh.graphs[i, j] = code
                sh.amounts[i, j] = amount

    def _widen(self, res: str, width: int) -> Shares:
        old = self.shares.get(res)
        new = Shares(np.zeros((self.n, width)), np.full((self.n, width), -1, dtype=np.int32))
        if old is not None:
            k = old.amounts.shape[1]
            new.amounts[:, :k] = old.amounts
            new.graphs[:, :k] = old.graphs
        self.shares[res] = new
        return new

    def _column(self, values: dict[int, Any], default: Any, dtype: Any) -> np.ndarray:
        col = np.full(self.n, default, dtype=dtype)
        if values:
            col[np.fromiter(values.keys(), dtype=np.intp, count=len(values))] = list(values.values())
        return col

    def _share_matrix(self, rows: dict[int, list[tuple[int, float]]]) -> Shares:
        width = max(len(r) for r in rows.values())
        out = Shares(np.zeros((self.n, width)), np.full((self.n, width), -1, dtype=np.int32))
        for i, entries in rows.items():
            for j, (code, amount) in enumerate(entries):
                out.graphs[i, j] = code
                out.amounts[i, j] = amount
        return out

    def _facts(self, i: int, s: PlatformState) -> tuple[dict, ...]:
        """One platform's facts, keyed per column family (see the constructor)."""
        p = s.platform
        numbers = [v for _k, v in p.capacities] + [v for _k, v in s.load] + [v for _k, v in p.properties]
        numbers += [a for _g, use in s.deployed for _r, a in use]
        if inexact(p.preference) or any(inexact(v) for v in numbers):
            self.inexact_rows.add(i)
        else:
            self.inexact_rows.discard(i)
        attrs = {}
        for key, value in p.attributes:
            codes = self.attr_code.setdefault(key, {})
            code = codes.get(repr(value))
            if code is None:
                code = codes[repr(value)] = len(codes)
                self.attr_text.setdefault(key, {}).setdefault(str(value), []).append(code)
            attrs[key] = code
        kinds: dict[str, int] = {}
        vendors: dict[tuple[str, str], int] = {}
        for d in s.devices:
            kinds[d.kind] = kinds.get(d.kind, 0) + 1
            vendors[(d.kind, d.vendor)] = vendors.get((d.kind, d.vendor), 0) + 1
        shares: dict[str, list[tuple[int, float]]] = {}
        for g, use in s.deployed:  # the order of PlatformState.used_by: deployments, then their uses
            code = self.graph_code.setdefault(g, len(self.graph_code))
            for res, amount in use:
                if amount:
                    shares.setdefault(res, []).append((code, amount))
        return dict(p.capacities), dict(s.load), dict(p.properties), attrs, kinds, vendors, shares
