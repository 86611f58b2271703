"""The repository: a labelled property graph on a networkx ``MultiDiGraph``.

Insert
    ``add_node`` / ``update_node`` / ``add_edge`` / ``remove_edge`` / ``relabel_edge``.
    Every change is appended to an append-only change log with its time and applied to
    the live graph: a node change at once, an edge change when :attr:`Repository.graph`
    is next read (the Query port and the Insert port's own reads use the repository's
    indexes and :attr:`Repository.node_data`, so a simulation that reads the graph no
    other way never pays for networkx's edge bookkeeping); :meth:`Repository.snapshot`
    replays the log up to a time.
Notify
    ``subscribe(callback, ops=..., labels=..., where=...)``: after each change the
    matching subscribers receive the frozen :class:`Change` record.
Query
    The named queries the algorithms use live in :mod:`desmon.repository.query`.

Node ids are ``"<Label>:<name>"``; unique edges use their label as key, history edges
``DEPLOYMENT_HISTORY#<seq>``.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any, Callable, Iterable, Iterator

import networkx as nx

from desmon.errors import QueryError
from desmon.model.checks import visible
from desmon.repository import labels as L

__all__ = ["Change", "Subscription", "Repository", "node_id", "graph_to_json", "graph_to_graphml", "jsonable"]

ADD_NODE = "add_node"
UPDATE_NODE = "update_node"
ADD_EDGE = "add_edge"
REMOVE_EDGE = "remove_edge"
RELABEL_EDGE = "relabel_edge"
OPS = (ADD_NODE, UPDATE_NODE, ADD_EDGE, REMOVE_EDGE, RELABEL_EDGE)


def node_id(label: str, name: str) -> str:
    """The repository id of the node ``name`` carrying ``label``."""
    return f"{label}:{name}"


@dataclass(frozen=True, slots=True)
class Change:
    """One entry of the change log (also what Notify delivers).

    For node changes ``node`` is set; for edge changes ``source``, ``target`` and
    ``key``. ``label`` is the node's or the edge's label (for a relabel: the new one,
    ``old_label`` the previous one). ``attrs`` are the attributes written.
    """

    seq: int
    time: float
    op: str
    label: str
    node: str | None = None
    source: str | None = None
    target: str | None = None
    key: str | None = None
    old_label: str | None = None
    attrs: tuple[tuple[str, Any], ...] = ()

    def attr(self, name: str, default: Any = None) -> Any:
        for k, v in self.attrs:
            if k == name:
                return v
        return default

    def describe(self) -> str:
        if self.node is not None:
            shown = ", ".join(f"{k}={v!r}" for k, v in self.attrs if k not in ("label", "requirement"))
            return f"{self.op} {self.node}" + (f" ({shown})" if shown else "")
        if self.op == RELABEL_EDGE:
            return f"{self.source} -[{self.old_label} => {self.label}]-> {self.target}"
        return f"{self.op} {self.source} -[{self.label}]-> {self.target}"


#: the slots of :class:`Change`, in field order, as their setters (see :func:`_change`)
_CHANGE_SETTERS = tuple(
    getattr(Change, name).__set__ for name in ("seq", "time", "op", "label", "node", "source", "target", "key", "old_label", "attrs")
)


def _change(
    seq: int, time: float, op: str, label: str, node: str | None, source: str | None, target: str | None, key: str | None,
    old_label: str | None, attrs: tuple[tuple[str, Any], ...],
) -> Change:
    """``Change(seq, time, ...)``, every field given, built without the frozen class's
    ``__init__`` (which sets each slot through ``object.__setattr__``): the repository
    writes one per change. Equal to the constructor's record (the class has no
    ``__post_init__``)."""
    change = object.__new__(Change)
    s_seq, s_time, s_op, s_label, s_node, s_source, s_target, s_key, s_old, s_attrs = _CHANGE_SETTERS
    s_seq(change, seq)
    s_time(change, time)
    s_op(change, op)
    s_label(change, label)
    s_node(change, node)
    s_source(change, source)
    s_target(change, target)
    s_key(change, key)
    s_old(change, old_label)
    s_attrs(change, attrs)
    return change


@dataclass(slots=True)
class Subscription:
    """Handle returned by :meth:`Repository.subscribe`."""

    callback: Callable[[Change], None]
    ops: frozenset[str] | None
    labels: frozenset[str] | None
    where: Callable[[Change], bool] | None
    active: bool = True

    def matches(self, change: Change) -> bool:
        if not self.active:
            return False
        if not self.routes(change.op, change.label, change.old_label):
            return False
        return self.where is None or bool(self.where(change))

    def routes(self, op: str, label: str, old_label: str | None) -> bool:
        """Do the ``ops`` and ``labels`` filters take a change of ``op`` and these labels?"""
        if self.ops is not None and op not in self.ops:
            return False
        return self.labels is None or label in self.labels or old_label in self.labels

    def cancel(self) -> None:
        self.active = False


def _apply(g: nx.MultiDiGraph, c: Change, attrs: dict[str, Any] | None = None) -> None:
    """Apply change ``c`` to ``g``; ``attrs``: ``dict(c.attrs)`` if the caller has it (it is not kept)."""
    if attrs is None:
        attrs = dict(c.attrs)
    if c.op == ADD_NODE:
        g.add_node(c.node, **attrs)
    elif c.op == UPDATE_NODE:
        g.nodes[c.node].update(attrs)
    elif c.op == ADD_EDGE:
        g.add_edge(c.source, c.target, key=c.key, **attrs)
    elif c.op == REMOVE_EDGE:
        g.remove_edge(c.source, c.target, key=c.key)
    elif c.op == RELABEL_EDGE:
        old = dict(g.get_edge_data(c.source, c.target, c.old_label))
        g.remove_edge(c.source, c.target, key=c.old_label)
        old.update(attrs)
        g.add_edge(c.source, c.target, key=c.key, **old)
    else:  # pragma: no cover - OPS is closed
        raise ValueError(c.op)


class Repository:
    """Insert / Query / Notify over a labelled property graph, with a change log."""

    def __init__(self, clock: Callable[[], float] | None = None) -> None:
        self._graph: nx.MultiDiGraph = nx.MultiDiGraph()
        #: the edge changes not applied to ``_graph`` yet, in order (:attr:`graph` applies them)
        self._unapplied: list[Change] = []
        #: node id -> its attributes (networkx's live node view: node changes apply at once)
        self.node_data = self._graph.nodes
        self._log: list[Change] = []
        self._subs: list[Subscription] = []
        self._clock = clock or (lambda: 0.0)
        self._order = 0
        #: bumped by every run-time requirement change (readers memoise specifications on it)
        self.specs_version = 0
        # (node, label) -> {neighbour: number of such edges}: keeps Query O(current edges)
        # however many DEPLOYMENT_HISTORY edges a long run accumulates on a node.
        self._out_index: dict[tuple[str, str], dict[str, int]] = {}
        self._in_index: dict[tuple[str, str], dict[str, int]] = {}
        # label -> {(source, target, key): None}: the edges carrying each label, so a
        # label's edges are read without a scan of every other edge
        self._label_index: dict[str, dict[tuple[str, str, str], None]] = {}
        # label -> {node id: None}, in insertion order (nodes are never removed)
        self._nodes_of: dict[str, dict[str, None]] = {}
        #: node id -> seq of the last change that touched it (the node itself, or an edge
        #: from or to it): readers memoise what they derive from a node and its edges on it
        self.touched: dict[str, int] = {}
        #: label -> seq of the last change that touched a node carrying it (a node change,
        #: or an edge from or to it): readers memoise what they derive from every node of
        #: a few labels on the stamps of those labels
        self.label_touched: dict[str, int] = {}
        #: node id -> seq of the last change of its own attributes (added or updated)
        self.node_updated: dict[str, int] = {}
        #: (node id, edge label) -> seq of the last change of an edge with that label from
        #: or to the node (a relabel stamps the old label and the new)
        self.edge_touched: dict[tuple[str, str], int] = {}
        #: edge label -> seq of the last change of an edge with that label (old and new, for a relabel)
        self.edges_changed: dict[str, int] = {}
        #: label -> seq of the last node change (added or updated) of a node carrying it:
        #: what a node's attributes say moves only with it
        self.label_updated: dict[str, int] = {}
        self._label_of: dict[str, str] = {}  # node id -> its label
        self._edge_label: dict[tuple[str, str, str], str] = {}  # (source, target, key) -> label, of every edge
        # (op, label, old label) -> the subscriptions whose ops and labels take such a
        # change, in subscription order (rebuilt after every subscribe)
        self._routes: dict[tuple[str, str, str | None], list[Subscription]] = {}

    @property
    def graph(self) -> nx.MultiDiGraph:
        """The labelled property graph (networkx), every change applied: the edge changes
        since the last read are applied now, in their order."""
        unapplied = self._unapplied
        if unapplied:
            g = self._graph
            for change in unapplied:
                _apply(g, change)
            unapplied.clear()
        return self._graph

    # -- clock and log ---------------------------------------------------------------
    def set_clock(self, clock: Callable[[], float]) -> None:
        self._clock = clock

    @property
    def now(self) -> float:
        return float(self._clock())

    @property
    def version(self) -> int:
        """The number of changes so far: equal versions, the same graph (readers memoise on it)."""
        return len(self._log)

    @property
    def log(self) -> tuple[Change, ...]:
        """The append-only change log."""
        return tuple(self._log)

    def _record(
        self, op: str, label: str, node: str | None = None, source: str | None = None, target: str | None = None,
        key: str | None = None, old_label: str | None = None, attrs: dict[str, Any] | None = None,
    ) -> Change:
        log = self._log
        seq = len(log)
        change = _change(seq, self.now, op, label, node, source, target, key, old_label, tuple(attrs.items()) if attrs else ())
        touched = self.touched
        stamps = self.label_touched
        if node is not None:
            _apply(self._graph, change, attrs or {})  # (a node change: at once)
            if op == ADD_NODE and node not in touched:
                self._nodes_of.setdefault(label, {})[node] = None
                self._label_of[node] = label
            touched[node] = self.node_updated[node] = seq
            stamps[label] = self.label_updated[label] = seq  # a node change carries the node's label
        else:
            self._unapplied.append(change)  # (an edge change: when the graph is next read)
            self._index(change)
            touched[source] = touched[target] = seq  # type: ignore[index]
            label_of = self._label_of
            stamps[label_of[source]] = stamps[label_of[target]] = seq  # type: ignore[index]
        log.append(change)
        route = (op, label, old_label)
        subs = self._routes.get(route)
        if subs is None:
            subs = self._routes[route] = [sub for sub in self._subs if sub.routes(op, label, old_label)]
        for sub in subs:
            if sub.active and (sub.where is None or sub.where(change)):
                sub.callback(change)
        return change

    def _index(self, c: Change) -> None:
        """The label and neighbour indexes after edge change ``c``."""
        op, source, target = c.op, c.source, c.target
        stamps = self.edge_touched
        seq = c.seq
        if op != ADD_EDGE:
            old = c.old_label if op == RELABEL_EDGE else c.label
            stamps[(source, old)] = stamps[(target, old)] = self.edges_changed[old] = seq  # type: ignore[index]
            gone = (source, target, c.old_label if op == RELABEL_EDGE else c.key)
            del self._label_index[old][gone]  # type: ignore[index]
            del self._edge_label[gone]  # type: ignore[arg-type]
            for bucket, b in ((self._out_index[(source, old)], target), (self._in_index[(target, old)], source)):  # type: ignore[index]
                n = bucket[b] - 1
                if n:
                    bucket[b] = n
                else:
                    del bucket[b]
        if op != REMOVE_EDGE:
            label = c.label
            stamps[(source, label)] = stamps[(target, label)] = self.edges_changed[label] = seq  # type: ignore[index]
            edge = (source, target, c.key)
            self._label_index.setdefault(label, {})[edge] = None  # type: ignore[index]
            self._edge_label[edge] = label  # type: ignore[index]
            bucket = self._out_index.setdefault((source, label), {})  # type: ignore[arg-type]
            bucket[target] = bucket.get(target, 0) + 1  # type: ignore[index]
            bucket = self._in_index.setdefault((target, label), {})  # type: ignore[arg-type]
            bucket[source] = bucket.get(source, 0) + 1  # type: ignore[index]

    def successors(self, nid: str, label: str) -> list[str]:
        """Targets of ``nid``'s out-edges labelled ``label`` (indexed: no scan of other edges)."""
        return list(self._out_index.get((nid, label), ()))

    def predecessors(self, nid: str, label: str) -> list[str]:
        """Sources of ``nid``'s in-edges labelled ``label`` (indexed)."""
        return list(self._in_index.get((nid, label), ()))

    # -- Insert ------------------------------------------------------------------------
    def add_node(self, label: str, name: str, **attrs: Any) -> str:
        """Create node ``label:name`` (or overwrite its attributes if it exists)."""
        nid = node_id(label, name)
        if nid in self._graph:
            self.update_node(nid, **attrs)
            return nid
        self._order += 1
        self._record(ADD_NODE, label, node=nid, attrs={"label": label, "name": name, "order": self._order, **attrs})
        return nid

    def update_node(self, nid: str, **attrs: Any) -> None:
        """Set attributes of an existing node."""
        label = self.node_label(nid)
        self._record(UPDATE_NODE, label, node=nid, attrs=attrs)

    def add_edge(self, source: str, target: str, label: str, key: str | None = None, **attrs: Any) -> str:
        """Create an edge ``source -[label]-> target``; unique labels use the label as key."""
        for n in (source, target):
            if n not in self._label_of:
                raise QueryError(f"the repository has no node {n!r}")
        key = key or label
        if (source, target, key) in self._edge_label:
            return key
        self._record(ADD_EDGE, label, source=source, target=target, key=key, attrs={"label": label, **attrs})
        return key

    def remove_edge(self, source: str, target: str, key: str) -> None:
        label = self._edge_label.get((source, target, key))
        if label is None:
            raise QueryError(f"no edge {source} -[{key}]-> {target} to remove")
        self._record(REMOVE_EDGE, label, source=source, target=target, key=key)

    def relabel_edge(self, source: str, target: str, old: str, new: str, **attrs: Any) -> str:
        """Relabel ``source -[old]-> target`` to ``new`` (a fresh unique key), adding ``attrs``."""
        if (source, target, old) not in self._edge_label:
            raise QueryError(f"no edge {source} -[{old}]-> {target} to relabel")
        key = f"{new}#{len(self._log)}"
        self._record(RELABEL_EDGE, new, source=source, target=target, key=key, old_label=old, attrs={"label": new, **attrs})
        return key

    # -- Notify ------------------------------------------------------------------------
    def subscribe(
        self,
        callback: Callable[[Change], None],
        *,
        ops: Iterable[str] | None = None,
        labels: Iterable[str] | None = None,
        where: Callable[[Change], bool] | None = None,
    ) -> Subscription:
        """Call ``callback(change)`` after every change matching all given filters."""
        if ops is not None:
            bad = set(ops) - set(OPS)
            if bad:
                raise QueryError(f"unknown change op(s) {sorted(bad)}: use {', '.join(OPS)}")
        sub = Subscription(
            callback,
            frozenset(ops) if ops is not None else None,
            frozenset(labels) if labels is not None else None,
            where,
        )
        self._subs.append(sub)
        self._routes = {}
        return sub

    # -- reading -----------------------------------------------------------------------
    def node_label(self, nid: str) -> str:
        try:
            return str(self.node_data[nid]["label"])
        except KeyError:
            raise QueryError(f"the repository has no node {nid!r}") from None

    def nodes(self, label: str) -> Iterator[tuple[str, dict[str, Any]]]:
        """(id, attributes) of every node with ``label``, in insertion order."""
        nodes = self.node_data
        for nid in list(self._nodes_of.get(label, ())):
            yield nid, nodes[nid]

    def node_ids(self, label: str) -> tuple[str, ...]:
        """The ids of every node with ``label``, in insertion order (indexed)."""
        return tuple(self._nodes_of.get(label, ()))

    def edges(self, label: str | None = None) -> Iterator[tuple[str, str, dict[str, Any]]]:
        """(source, target, attributes) of every edge (with ``label``, if given), in the
        graph's order."""
        for s, t, data in self.graph.edges(data=True):
            if label is None or data.get("label") == label:
                yield s, t, data

    def labelled(self, label: str) -> list[tuple[str, str, str]]:
        """(source, target, key) of every edge labelled ``label`` (indexed, in the order
        they got the label; not the graph's order)."""
        return list(self._label_index.get(label, ()))

    def snapshot(self, at: float | None = None, *, upto: int | None = None) -> nx.MultiDiGraph:
        """The graph as it was at time ``at`` (all changes with time <= at), or after its
        first ``upto`` changes (a :attr:`version`: of two events at one time, the state
        between them); a copy."""
        g = nx.MultiDiGraph()
        for change in self._log if upto is None else self._log[:upto]:
            if at is not None and change.time > at:
                break
            _apply(g, change)
        return g


# -- exports ---------------------------------------------------------------------------
def jsonable(value: Any) -> Any:
    """``value`` as plain JSON: numbers, strings, lists and string-keyed objects (a model
    object by its description)."""
    if isinstance(value, (str, int, float, bool)) or value is None:
        return value
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    describe = getattr(value, "describe", None)
    if callable(describe):
        return describe()
    return str(value)


#: Node attributes that hold the model objects themselves; exports show their flattened fields.
OBJECT_ATTRS = frozenset({"platform", "device", "spec", "declared", "requirement"})


def graph_to_json(g: nx.MultiDiGraph) -> dict[str, Any]:
    """A stable JSON-able dict of a snapshot: nodes and edges sorted, attributes flattened."""
    nodes = [
        {"id": n, **{k: jsonable(v) for k, v in sorted(d.items()) if k not in OBJECT_ATTRS}}
        for n, d in sorted(g.nodes(data=True))
    ]
    edges = [
        {"source": s, "target": t, "key": k, **{a: jsonable(v) for a, v in sorted(d.items())}}
        for s, t, k, d in sorted(g.edges(keys=True, data=True), key=lambda e: (e[0], e[1], str(e[2])))
    ]
    return {"nodes": nodes, "edges": edges}


def graph_to_graphml(g: nx.MultiDiGraph, path: str) -> None:
    """Write a snapshot as GraphML (non-scalar attributes as JSON strings). Every text is
    :func:`~desmon.model.checks.visible` (a character XML cannot hold is written as its
    escape) and XML-escaped by the writer, so the file parses whatever a name holds."""
    out = nx.MultiDiGraph()

    def scalar(v: Any) -> Any:
        v = jsonable(v)
        if isinstance(v, str):
            return visible(v)
        return v if isinstance(v, (int, float, bool)) else visible(json.dumps(v, sort_keys=True))

    def key(k: Any) -> Any:
        return visible(k) if isinstance(k, str) else k

    for n, d in g.nodes(data=True):
        out.add_node(key(n), **{visible(k): scalar(v) for k, v in d.items() if v is not None and k not in OBJECT_ATTRS})
    for s, t, k, d in g.edges(keys=True, data=True):
        out.add_edge(key(s), key(t), key=key(k), **{visible(a): scalar(v) for a, v in d.items() if v is not None})
    nx.write_graphml(out, path)


__all__ += ["ADD_NODE", "UPDATE_NODE", "ADD_EDGE", "REMOVE_EDGE", "RELABEL_EDGE", "OPS"]
