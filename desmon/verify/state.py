"""A compact, state-backed Query + Insert + Control for the checker.

:class:`Key` is the frozen, hashable, canonical state: context, failed devices, platforms
down, background loads, active deployments and standing errors, every unordered part
sorted. :class:`StateStore` is loaded from a key, answers the QueryPort exactly as
:class:`~desmon.repository.query.RepositoryQuery` over the networkx repository would
(``tests/test_state_equivalence.py`` shows it with hypothesis), takes the context
monitor's Insert facts, and executes Control commands by the one Control semantics of
:mod:`desmon.deployment.control`; a start the rules allow follows an *outcome prefix*:
a start beyond the prefix succeeds and marks a choice point the checker may branch on.

Performance: the store holds the key's parts as the very (immutable, sorted) tuples
of the key, so :meth:`StateStore.load` is a handful of attribute assignments and
:meth:`StateStore.key` shares them. A mutation rebuilds one small tuple. Every answer
derived from the parts is memoised on the parts themselves (pure functions of
hashable tuples): the platform states of a (failed, down, loads, deployed) combination,
and the per-graph / per-platform index of a deployment set. Because the same facts
always give the very same platform-states tuple, the deployer's validity answers are
memoised per store on that tuple's identity (:attr:`StateStore.validity_memo`, read by
:func:`~desmon.deployment.validity.validity_for`). The memos are bounded
(cleared when they grow past :data:`MEMO_LIMIT` entries), so memory stays flat on
long runs; a cleared memo only costs recomputation.
"""

from __future__ import annotations

from typing import Any, Callable, NamedTuple

from desmon.deployment.control import ControlRules
from desmon.deployment.invariants import SystemView, Invariant, make_view
from desmon.errors import QueryError
from desmon.model.events import RequirementChange
from desmon.model.requirements import DeploymentSpec, Requirement
from desmon.model.system import PlatformState, SystemModel, with_load

__all__ = ["Key", "StateStore", "StoreInsert", "MEMO_LIMIT"]

#: Entries a store memo may hold before it is cleared.
MEMO_LIMIT = 50_000


class Key(NamedTuple):
    """The checker's state. Platforms and devices are named; every set is a sorted tuple."""

    context: str | None
    failed: tuple[str, ...]
    down: tuple[str, ...]
    # (platform, sorted (resource, amount)) for nonzero loads only: a zero amount has no
    # entry and a platform without load is absent, so one state has exactly one key
    loads: tuple[tuple[str, tuple[tuple[str, float], ...]], ...]
    deployments: tuple[tuple[str, str], ...]  # sorted (graph, platform)
    standing: tuple[str, ...]
    # (graph, current requirements) of every graph whose requirements a RequirementChange
    # made differ from the declared ones, sorted by graph; () while none did
    specs: tuple[tuple[str, tuple], ...] = ()


_new_tuple = tuple.__new__


class _ByPlatform(dict):
    """platform -> active graphs (every platform present); unknown platform: QueryError."""

    __slots__ = ()

    def __missing__(self, platform: str) -> tuple[str, ...]:
        raise QueryError(f"unknown platform {platform!r}")


class _ByGraph(dict):
    """graph -> platforms it is active on; a graph without a specification: ()."""

    __slots__ = ()

    def __missing__(self, graph: str) -> tuple[str, ...]:
        return ()


class _Deployments(dict):
    """deployment -> its perception graph (the identity); unknown deployment: QueryError."""

    __slots__ = ()

    def __missing__(self, deployment: str) -> str:
        raise QueryError(f"unknown deployment {deployment!r}")


class StateStore:
    """QueryPort + InsertPort + ControlPort over the parts of one :class:`Key`."""

    #: requirements never change behind the store's back: nothing is memoised on a version
    specs_version = None

    def __init__(self, model: SystemModel, checks: Any = None, make_state: Callable[..., Any] = PlatformState) -> None:
        self.model = model
        #: what builds the platform states it hands out from (platform, up, devices, load,
        #: deployed): PlatformState, or the table engine's recording checks, which hand
        #: out opaque handles (:class:`~desmon.deployment.ports.PlatformHandle`)
        self.make_state = make_state
        #: the Checks port requirement questions about its platforms go to (the Query
        #: port's and the Control rules'; None: the default memoised checks)
        self.checks = checks
        self.platform_names = tuple(p.name for p in model.platforms)
        self._order = {p: i for i, p in enumerate(self.platform_names)}
        self._platform = {p.name: p for p in model.platforms}
        self._device_platform = {d.name: d.platform for d in model.devices}
        self._devices_on = {p.name: tuple(d for d in model.devices if d.platform == p.name) for p in model.platforms}
        self._spec = {s.graph: s for s in model.specs}
        self._graphs = {g.name for g in model.graphs}
        self._use = {s.graph: s.consumption() for s in model.specs}
        self._ps_cache: dict[tuple, PlatformState] = {}
        self.rules = ControlRules(model, self._current, checks)
        #: why the last start was refused by the Control rules ("" when it was not)
        self.refused = ""
        #: the world's own refusal of a start, (graph, platform) -> reason or None, where
        #: the physical world differs from what the repository knows (``desmon analyze``:
        #: a platform gone but not yet noticed refuses the start, as in the simulation)
        self.physical: Callable[[str, str], str | None] | None = None
        self._use_memo: dict[tuple[str, ...], tuple] = {}
        self._states_memo: dict[tuple, tuple[PlatformState, ...]] = {}
        self._index_memo: dict[tuple, tuple] = {}
        self._standing_memo: dict[frozenset[str], tuple[str, ...]] = {}
        #: per-store memo of :func:`~desmon.deployment.validity.validity_for` (see there):
        #: sound because :meth:`platform_states` returns one tuple object per facts
        self.validity_memo: dict = {}
        # mutable state: the key's parts, as sorted tuples
        self.ctx: str | None = None
        self.failed: tuple[str, ...] = ()
        self.down: tuple[str, ...] = ()
        self.loads: tuple[tuple[str, tuple[tuple[str, float], ...]], ...] = ()
        self.deployed: tuple[tuple[str, str], ...] = ()
        #: the key's ``specs`` part: requirements changed at run time (see :meth:`change_requirements`)
        self.specs_now: tuple[tuple[str, tuple], ...] = ()
        self._spec_memo: dict[tuple[str, tuple], DeploymentSpec] = {}
        self._specs_memo: dict[tuple, tuple[DeploymentSpec, ...]] = {}
        self._states: tuple[PlatformState, ...] | None = None
        self._touched: set[str] = set()
        self.perception_graph = _Deployments({g: g for g in self._spec}).__getitem__  # type: ignore[method-assign]
        self._set_index()
        # control
        self.prefix: tuple[bool, ...] = ()
        self.outcomes: list[bool] = []
        self.watch: tuple[Invariant, ...] = ()
        #: ``(graph, platform) -> [(invariant, message)]``: the instantaneous invariants a start broke (set by the checker)
        self.watch_check: Callable[[str, str], list[tuple[str, str]]] | None = None  # (graph, platform) started
        self.watch_view: "Callable[[], SystemView] | None" = None  # fallback: a view to check self.watch on
        #: what the reaction broke so far, as (invariant, message, after command): the first
        #: watched invariant it broke, or with ``every`` the first violation of each
        self.instant: tuple[tuple[str, str, str], ...] = ()
        self.every = False

    # -- state --------------------------------------------------------------------------
    def load(self, key: Key) -> None:
        self.ctx = key.context
        self.failed = key.failed
        self.down = key.down
        self.loads = key.loads
        self.deployed = key.deployments
        self.specs_now = key.specs
        # the key's platform states are usually memoised (the checker evaluated the
        # invariants on it when it was new): take them now, so that the event's
        # mutation only recomputes the platform it touches
        self._states = self._states_memo.get(
            (key.failed, key.down, key.loads, key.deployments, key.specs) if key.specs else (key.failed, key.down, key.loads, key.deployments)
        )
        self._touched.clear()
        self._set_index()

    def facts(self) -> tuple:
        """The parts every platform state derives from (a memo key)."""
        if self.specs_now:
            return (self.failed, self.down, self.loads, self.deployed, self.specs_now)
        return (self.failed, self.down, self.loads, self.deployed)

    def key(self, standing: frozenset[str] | tuple[str, ...] = ()) -> Key:
        if isinstance(standing, frozenset):
            s = self._standing_memo.get(standing)
            if s is None:
                s = self._standing_memo[standing] = tuple(sorted(standing))
        else:
            s = tuple(sorted(standing))
        # tuple.__new__ builds the same Key (fields in declaration order) without the
        # NamedTuple's Python-level __new__: this runs once per checker transition
        return _new_tuple(Key, (self.ctx, self.failed, self.down, self.loads, self.deployed, s, self.specs_now))

    def begin(self, prefix: tuple[bool, ...] = ()) -> None:
        """Start executing a reaction: starts follow ``prefix``, then succeed."""
        self.prefix = prefix
        self.outcomes = []
        self.instant = ()

    # -- QueryPort ----------------------------------------------------------------------
    def _current(self, graph: str) -> DeploymentSpec | None:
        """The specification of ``graph`` with its current requirements."""
        declared = self._spec.get(graph)
        if declared is None or not self.specs_now:
            return declared
        for g, reqs in self.specs_now:
            if g == graph:
                spec = self._spec_memo.get((g, reqs))
                if spec is None:
                    spec = self._spec_memo[(g, reqs)] = DeploymentSpec(g, reqs, declared.fixed_platform, declared.rebalance, declared.reads)
                return spec
        return declared

    def current_specs(self) -> tuple[DeploymentSpec, ...]:
        """Every specification of the model with its current requirements (memoised)."""
        if not self.specs_now:
            return self.model.specs
        out = self._specs_memo.get(self.specs_now)
        if out is None:
            out = self._specs_memo[self.specs_now] = tuple(self._current(s.graph) or s for s in self.model.specs)
        return out

    def deployment_information(self, graph: str) -> DeploymentSpec | None:
        return self._current(graph) if graph in self._graphs else None

    def fixed_platform(self, spec: DeploymentSpec) -> str | None:
        s = self._spec.get(spec.graph)
        return s.fixed_platform if s is not None else None

    def constraints(self, spec: DeploymentSpec) -> tuple[Requirement, ...]:
        s = self._current(spec.graph)
        return s.requirements if s is not None else ()

    def _load_of(self, platform: str) -> tuple[tuple[str, float], ...]:
        for p, items in self.loads:
            if p == platform:
                return items
        return ()

    def platform_state(self, platform: str) -> PlatformState:
        devs = self._devices_on.get(platform)
        if devs is None:
            raise QueryError(f"unknown platform {platform!r}")
        failed = self.failed
        devices = tuple(d for d in devs if d.name not in failed) if failed else devs
        load = self._load_of(platform) if self.loads else ()
        graphs = self.active_deployments(platform)  # sorted by graph, as the repository's
        if self.specs_now:
            deployed = tuple((g, self._consumption(g)) for g in graphs)
        else:
            deployed = self._use_memo.get(graphs)
            if deployed is None:
                deployed = self._use_memo[graphs] = tuple((g, self._use.get(g, ())) for g in graphs)
        up = platform not in self.down
        ck = (platform, up, devices, load, deployed)
        st = self._ps_cache.get(ck)
        if st is None:
            if len(self._ps_cache) > MEMO_LIMIT:
                self._ps_cache.clear()
            st = self.make_state(self._platform[platform], up, devices, load, deployed)
            self._ps_cache[ck] = st
        return st

    def _consumption(self, graph: str) -> tuple:
        spec = self._current(graph)
        return spec.consumption() if spec is not None else ()

    def platform_states(self) -> tuple[PlatformState, ...]:
        """Every platform's state, in declaration order.

        The tuple is memoised per facts, and the memo is consulted before any platform
        is recomputed: the same facts always yield the very same tuple object, which is
        what lets :func:`~desmon.deployment.validity.validity_for` memoise on its
        identity (see :attr:`validity_memo`). On a miss after a mutation only the
        touched platforms are recomputed.
        """
        states = self._states
        if states is not None and not self._touched:
            return states
        fk = self.facts()
        memo = self._states_memo
        known = memo.get(fk)
        if known is not None:
            self._touched.clear()
            self._states = known
            return known
        if states is None:
            states = tuple(self.platform_state(p) for p in self.platform_names)
        else:
            # a mutation changed only the touched platforms: recompute just those
            lst = list(states)
            for p in self._touched:
                lst[self._order[p]] = self.platform_state(p)
            self._touched.clear()
            states = tuple(lst)
        if len(memo) > MEMO_LIMIT:
            memo.clear()
        memo[fk] = self._states = states
        return states

    def _touch(self, platform: str) -> None:
        if self._states is not None:
            self._touched.add(platform)

    # deployed_on / active_deployments / perception_graph are, per deployment set, plain
    # dictionary lookups: the instance attributes of the same names are rebound to the
    # ``__getitem__`` of memoised index dicts whenever the deployment set changes (see
    # :meth:`_set_index`); the methods below are the documented fallbacks.
    def _set_index(self) -> None:
        deployed = self.deployed
        idx = self._index_memo.get(deployed)
        if idx is None:
            by_graph: dict[str, list[str]] = {}
            by_platform: dict[str, list[str]] = {p: [] for p in self.platform_names}
            for g, p in deployed:
                by_graph.setdefault(g, []).append(p)
                by_platform[p].append(g)
            if len(self._index_memo) > MEMO_LIMIT:
                self._index_memo.clear()
            idx = self._index_memo[deployed] = (
                _ByGraph({g: tuple(sorted(ps)) for g, ps in by_graph.items() if g in self._spec}).__getitem__,
                _ByPlatform({p: tuple(sorted(gs)) for p, gs in by_platform.items()}).__getitem__,
            )
        self.deployed_on, self.active_deployments = idx  # type: ignore[method-assign]

    def deployed_on(self, graph: str) -> tuple[str, ...]:  # rebound per deployment set
        raise AssertionError("unreachable: rebound in _set_index")  # pragma: no cover

    def active_deployments(self, platform: str) -> tuple[str, ...]:  # rebound per deployment set
        raise AssertionError("unreachable: rebound in _set_index")  # pragma: no cover

    def perception_graph(self, deployment: str) -> str:  # rebound in __init__
        raise AssertionError("unreachable: rebound in __init__")  # pragma: no cover

    def context(self) -> str | None:
        return self.ctx

    def deployments(self) -> tuple[tuple[str, str], ...]:
        return self.deployed

    # -- InsertPort ---------------------------------------------------------------------
    # -- ControlPort (the Control rules; starts they allow follow the outcome prefix) ------
    def start(self, graph: str, platform: str) -> bool:
        pair = (graph, platform)
        if pair in self.deployed:
            return True
        # a start the rules refuse is no choice point: it fails in every branch, and does
        # not take a position of the outcome prefix (desmon.deployment.control). The rules
        # read the world's facts: the physical ones where they are given (desmon analyze's
        # chain, whose repository may not have noticed a failure or a repair yet), as the
        # simulation's infrastructure does; else the store's own
        physical = self.physical
        why = self.rules.start_refusal(graph, platform, self.platform_state) if physical is None else physical(graph, platform)
        self.refused = why or ""
        if why is not None:
            return False
        i = len(self.outcomes)
        ok = self.prefix[i] if i < len(self.prefix) else True
        self.outcomes.append(ok)
        if ok:
            self.deployed = tuple(sorted(self.deployed + (pair,)))
            self._touch(platform)
            self._set_index()
            self._watch(pair)
        return ok

    def stop(self, graph: str, platform: str) -> bool:
        pair = (graph, platform)
        if pair not in self.deployed:
            return False
        self.deployed = tuple(d for d in self.deployed if d != pair)
        self._touch(platform)
        self._set_index()
        return True  # (a stop breaks no instantaneous invariant: desmon.deployment.invariants.start_findings)

    def _watch(self, pair: tuple[str, str]) -> None:
        """The watched invariants the start of ``pair`` broke (:func:`~desmon.deployment.invariants.start_findings`)."""
        found = self.instant
        if not self.watch or (found and (not self.every or len(found) == len(self.watch))):
            return
        if self.watch_check is not None:
            bad = self.watch_check(*pair)
        elif self.watch_view is not None:
            from desmon.deployment.invariants import start_findings

            bad = start_findings(self.watch_view(), self.watch, *pair)
        else:
            return
        if bad:
            known = {f[0] for f in found}
            new = [(name, msg, f"start {pair[0]} on {pair[1]}") for name, msg in bad if name not in known]
            self.instant = found + tuple(new if self.every else new[:1])



class StoreInsert:
    """The Insert port over a :class:`StateStore`: the context monitor writes an event's
    facts into the store's key parts (the store is the Query and Control ports)."""

    __slots__ = ("store",)

    def __init__(self, store: StateStore) -> None:
        self.store = store

    def set_context(self, context: str) -> bool:
        if self.store.ctx == context:
            return False
        self.store.ctx = context
        return True

    def set_device_working(self, device: str, working: bool) -> str | None:
        if device not in self.store._device_platform:
            raise QueryError(f"unknown device {device!r}: it is not in the repository")
        if (device not in self.store.failed) == working:
            return None
        if working:
            self.store.failed = tuple(d for d in self.store.failed if d != device)
        else:
            self.store.failed = tuple(sorted(self.store.failed + (device,)))
        platform = self.store._device_platform[device]
        self.store._touch(platform)
        return platform

    def set_platform_up(self, platform: str, up: bool) -> bool:
        if platform not in self.store._platform:
            raise QueryError(f"unknown platform {platform!r}: it is not in the repository")
        if (platform not in self.store.down) == up:
            return False
        if up:
            self.store.down = tuple(p for p in self.store.down if p != platform)
        else:
            self.store.down = tuple(sorted(self.store.down + (platform,)))
        self.store._touch(platform)
        return True

    def set_load(self, platform: str, resource: str, amount: float) -> bool:
        if platform not in self.store._platform:
            raise QueryError(f"unknown platform {platform!r}: it is not in the repository")
        cur = with_load(dict(self.store._load_of(platform)), resource, amount)
        if cur is None:
            return False
        # a platform without load has no entry either (as in the initial state)
        loads = dict(self.store.loads)
        if cur:
            loads[platform] = tuple(sorted(cur.items()))
        else:
            del loads[platform]
        self.store.loads = tuple((p, loads[p]) for p in self.store.platform_names if p in loads)
        self.store._touch(platform)
        return True

    def change_requirements(self, change: RequirementChange) -> tuple[str, ...] | None:
        """Apply a requirement change: the key's ``specs`` part follows (a graph whose
        requirements are the declared ones again has no entry). Returns the platforms
        the graph is deployed on (their states change with its consumption), or None."""
        declared = self.store._spec.get(change.graph)
        if declared is None:
            raise QueryError(f"{change}: no deployment specification for {change.graph!r} in the repository")
        current = self.store._current(change.graph)
        assert current is not None
        new = change.apply(current.requirements, declared.requirements)
        if new == current.requirements:
            return None
        others = tuple((g, r) for g, r in self.store.specs_now if g != change.graph)
        mine = () if new == declared.requirements else ((change.graph, new),)
        self.store.specs_now = tuple(sorted(others + mine))
        hosts = self.store.deployed_on(change.graph)
        for p in self.store.platform_names:  # every platform's deployed shares may read the graph's consumption
            self.store._touch(p)
        return hosts


def view_from(store: StateStore, standing: frozenset[str], slots: tuple[tuple[str, ...], ...]) -> SystemView:
    return make_view(store.platform_states(), store.current_specs(), standing, slots, checks=store.checks)
