"""The table engine: the checker's BFS with every distinct reaction run once.

The direct engine (:mod:`desmon.verify.direct`) runs the real deployment core for each of the millions of
transitions of a large scenario. Most of those runs repeat one another: a reaction reads
the context, the deployments and the standing errors, and of the platforms only *which
of them pass the requirement checks* it asks about. This engine runs the same real
core, but only once per distinct reading, and replays what it did everywhere else.

How a reaction is memoised
    A state is an environment code (context and the current requirements of each graph
    that requirement changes reach, as one *global* digit; failed devices, platforms down
    or absent (on demand), load levels: one mixed-radix digit per platform) and an
    interned system part (deployments, standing errors). A transition's *root* is
    (system part, global digit after the event, what the event changed, failed-start
    prefix). The first time a root is
    met, the real core runs on the real state while :mod:`desmon.deployment.validity`
    hands every requirement check to an observer (``validity._observer``). The observer
    answers with the real result, wrapped so that what the run *uses* of it is recorded:
    whether one platform is acceptable, the acceptable platforms one by one in preference
    order as far as the run iterates, or every answer down to the failure texts (see
    :class:`_Recorder`). With preferences the order of the acceptable platforms, their
    scores, gains and score breakdown derive from every platform's score: using them
    observes each platform's *score key* (rejected, or the number of its (score,
    breakdown) among those the platform's facts can give). The run becomes a path in a decision tree: one node per
    observation, one branch per answer, a leaf with what the reaction did (next system
    part, start outcomes, deployer branches, an instantaneous violation). Other
    transitions with the same root walk the tree; each observation is answered from a
    table of per-platform results (computed by the same requirement code on the same
    platform facts, indexed by the platform's digit), and a leaf gives the successor. A
    transition whose answers leave the tree runs the real core again, which extends the
    tree. The invariants of each new state are memoised the same way, on (system part,
    context). Events, tree walks and duplicate detection are numpy operations over a
    batch of a BFS level.

Why it is sound
    A reaction is a deterministic function of what it reads through the ports (the
    checker already relies on that: a replay that disagrees is reported as
    nondeterminism). The context, deployments and standing errors are in the root, the
    requirement checks are observed, and the platforms' facts cannot be read any other
    way: while a run is recorded the core's Query port offers only the QueryPort
    methods, and its platform states are guarded: reading ``up``, ``devices`` or
    ``load`` (or comparing two states) anywhere but inside a requirement check the
    observer is answering stops the run with :class:`UnobservedRead` (``--engine auto``
    then falls back to the direct engine). A check on facts that are not the state's
    own (a port that rewrites them, or swaps the platform) is refused the same way, and
    so is a check's result used as what its wrapper is not. Every recording re-checks
    the environment code and the stimulus, and a recording that contradicts the tree is
    a :class:`~desmon.errors.NondeterminismError`. Assumed beyond determinism: a
    reaction does not branch on the *type* of a check's result (the wrappers are not
    tuples or strings) or on a platform state's hash value (recorded states hash by
    identity), and does not deliberately bypass the guard (e.g. through the base
    class's slot descriptors). Counterexamples are rebuilt by replaying their
    events through the real core, as in the direct engine.

The result (states and their order, transitions, every counter, counterexamples) is
the direct engine's, for every scenario shipped (``tests/test_verify_table.py``).
Symmetry reduction is left to the direct engine.
"""

from __future__ import annotations

import sys
from array import array
from typing import Any, Callable, Iterator, NamedTuple, Sequence

import numpy as np
import numpy.ma  # noqa: F401  (np.unique imports it on first use, leaving cyclic garbage: not during a search)

from desmon.deployment import validity as _validity
from desmon.deployment.core import DeploymentCore
from desmon.deployment.guard import CRASH, ReactionStopped
from desmon.errors import CheckerError, NondeterminismError
from desmon.model.events import (
    ActionChange, DeviceFail, DeviceRepair, Event, LoadChange, PlatformDown, PlatformJoin, PlatformLeave, PlatformUp,
    RequirementChange, event_kind,
)
from desmon.model.requirements import Preference
from desmon.model.system import PlatformState
from desmon.verify.environment import EVENT_KINDS
from desmon.verify.search import INTERRUPTED, Budget, CheckResult, Trail, final_status as _final_status
from desmon.verify.state import Key, StateStore
from desmon.verify.system import RECHECK_EVERY, RECHECK_FIRST, TransitionSystem, command_key
from desmon.verify.trace import KEPT_BRANCH, Counterexample, branch_name

__all__ = ["TableEngine", "TableUnsupported", "UnobservedRead", "table_unsupported", "CHUNK_STATES"]

#: bits of a state code that hold the interned system part (deployments, standing)
SYS_BITS = 24
_SYS_MASK = (1 << SYS_BITS) - 1
#: a decision tree's root key packs (system part, context digit, stimulus, prefix) into
#: one int64: 24 + 10 + 13 + 16 bits (each limit is checked where its part is made)
_ROOT_CTX, _ROOT_STIM, _ROOT_PREFIX = 10, 13, 16


#: combinations of one platform's facts the engine tabulates answers for (beyond: direct engine)
MAX_DIGITS = 4096
#: frontier states expanded per numpy batch (bounds the memory of one batch)
CHUNK_STATES = 16_384
#: new states added between two looks at the search's budget (time, memory, Ctrl-C)
LOOK_EVERY = 64
_KIND_ID = {k: i for i, k in enumerate(EVENT_KINDS)}


def _root_key(system: np.ndarray, ctx: np.ndarray, stim: np.ndarray | int, prefix: np.ndarray | int) -> np.ndarray:
    """The decision-tree root of each (system part, context digit, stimulus, prefix)."""
    return (((system << _ROOT_CTX | ctx) << _ROOT_STIM | stim) << _ROOT_PREFIX) | prefix


class _PlainRun(tuple):
    """A transition run on the direct engine's store (:meth:`TransitionSystem.run_one`),
    standing for a recorded run that failed on the deployer's own TypeError or AttributeError."""


class TableUnsupported(CheckerError):
    """The table engine cannot run this search (``--engine auto`` falls back to the direct engine)."""


class UnobservedRead(TableUnsupported):
    """A reaction read a platform fact outside the requirement checks: it cannot be memoised."""


def _count(counter: Any, names: Sequence[Any], values: np.ndarray, size: int) -> None:
    """Add the occurrences of each number in ``values`` to ``counter`` under its name."""
    for k, n in enumerate(np.bincount(values, minlength=size).tolist()):
        if n:
            counter[names[k]] += n


class _Spent(Exception):
    """The search's budget ran out inside a batch (between two recorded runs or walk rounds):
    the batch is dropped, nothing of it having been counted yet."""


# ------------------------------------------------------------------------------------
# recording: the observer of requirement checks and the guarded platform states
# ------------------------------------------------------------------------------------


class _Recorder:
    """Observer of the requirement checks of one recorded run (see ``validity._observer``).

    It answers each check with the real result, wrapped so that the run's *use* of it
    is what gets recorded: asking whether one platform is acceptable observes that
    platform's answer only; iterating, truth-testing or indexing the acceptable
    platforms observes them one by one in preference order (up to where the code
    stops); anything else (length, slicing, comparing, the rejected platforms and their
    reasons) observes every answer, down to the failure texts when those are read; an
    explanation is observed only where its text is used.
    """

    def __init__(self, engine: "TableEngine") -> None:
        self.engine = engine
        self.inside = 0
        self.obs: list[tuple[tuple, int]] = []
        #: the observations of this run so far (an observation made again adds nothing)
        self.made: set[tuple] = set()
        self.store: StateStore | None = None

    def observe(self, desc: tuple, code: int) -> None:
        """Record that the run observed answer ``code`` to ``desc`` (once per run: the same
        question on the same path always has the same answer)."""
        if desc not in self.made:
            self.made.add(desc)
            self.obs.append((desc, code))

    def validity(self, reqs: tuple, states: tuple[PlatformState, ...], graph: str | None, reasons: bool) -> Any:
        self.inside += 1
        try:
            parts = self._parts(states)
            fails = [_validity._check_platform(reqs, st, graph, not reasons) for st in states]
            real = _validity._check_validity(reqs, states, graph, reasons)
            at = {id(st): i for i, st in enumerate(states)}
            order = [at[id(st)] for st in _validity.order_platforms(states)]
            ranked = any(type(r) is Preference for r in reqs)
            scored = [None if f else _score_key(reqs, st, graph) for f, st in zip(fails, states)] if ranked else None
        finally:
            self.inside -= 1
        check = _Check(self, reqs, graph, not reasons, parts, fails, [st.platform.name for st in states], scored)
        acceptable = _Acceptable(check, real.acceptable, order)
        if not ranked:
            return _ObservedValidity(acceptable, _Reasons(check, real.rejected))  # type: ignore[arg-type]
        # with preferences the order of the acceptable platforms, their scores and the
        # breakdown are observed as the scores of every platform ("rank")
        breakdown = _Ranked(check, real.breakdown, acceptable) if real.breakdown else ()
        return _ObservedValidity(acceptable, _Reasons(check, real.rejected), _Ranked(check, real.scores, acceptable), breakdown)  # type: ignore[arg-type]

    def platform(self, reqs: tuple, state: PlatformState, graph: str | None, first_only: bool) -> Any:
        self.inside += 1
        try:
            parts = self._parts((state,))
            fails = _validity._check_platform(reqs, state, graph, first_only)
        finally:
            self.inside -= 1
        return _Reasons(_Check(self, reqs, graph, first_only, parts, [fails], [state.platform.name]), fails, single=True)

    def _parts(self, states: tuple[PlatformState, ...]) -> tuple[tuple[int, int], ...]:
        """(platform index, interned deployments) of each state, after checking its facts are the state's own."""
        eng = self.engine
        store = self.store
        assert store is not None
        own = store.platform_states()
        index = eng.platform_index
        parts = []
        for s in states:
            name = s.platform.name
            p = index[name]
            canonical = own[p]
            if s is not canonical and (s.platform, s.up, s.devices, s.load) != (canonical.platform, canonical.up, canonical.devices, canonical.load):
                raise UnobservedRead(
                    f"a requirement check saw platform {name} with facts that are not the state's own "
                    f"(platform={s.platform}, up={s.up}, devices={[d.name for d in s.devices]}, load={s.load}): the table engine cannot "
                    "memoise a port that rewrites platform facts; run with --engine direct"
                )
            parts.append((p, eng.intern_deployed(s.deployed)))
        return tuple(parts)


def _score_key(reqs: tuple, state: PlatformState, graph: Any) -> tuple:
    """What the preferences make of one acceptable platform: its score and the weighted
    terms it is the sum of (what ``Validity.breakdown`` shows)."""
    return (_validity.platform_score(reqs, state, graph), _validity.score_breakdown(reqs, state, graph))


class _Check:
    """One requirement check's real answers, and how to record observing them."""

    __slots__ = ("rec", "table", "first_only", "parts", "fails", "names", "scored")

    def __init__(self, rec: _Recorder, reqs: tuple, graph: str | None, first_only: bool,
                 parts: tuple[tuple[int, int], ...], fails: list[tuple], names: list[str],
                 scored: list[tuple | None] | None = None) -> None:
        self.rec = rec
        self.table = rec.engine.intern_table(reqs, graph)
        self.first_only = first_only
        self.parts = parts
        self.fails = fails
        self.names = names
        self.scored = scored  # each platform's score key (None: rejected), with preferences

    def ok(self, which: Sequence[int]) -> None:
        """Observe whether the platforms at positions ``which`` pass."""
        code = 0
        for j, i in enumerate(which):
            code |= (not self.fails[i]) << j
        self.rec.observe(("ok", self.table, None, tuple(self.parts[i] for i in which)), code)

    def why(self) -> None:
        """Observe every platform's failures, reasons included."""
        eng = self.rec.engine
        code, mult = 0, 1
        for (p, dep), f in zip(self.parts, self.fails):
            value, radix = eng.failure_id(self.table, self.first_only, p, dep, f)
            code += value * mult
            mult *= radix
        self.rec.observe(("why", self.table, self.first_only, self.parts), code)

    def rank(self) -> None:
        """Observe every platform's acceptability and score (with preferences: what the
        order of the acceptable platforms, their scores and the breakdown derive from)."""
        assert self.scored is not None
        eng = self.rec.engine
        code, mult = 0, 1
        for (p, dep), key in zip(self.parts, self.scored):
            value, radix = eng.score_id(self.table, p, dep, key)
            code += value * mult
            mult *= radix
        self.rec.observe(("rank", self.table, None, self.parts), code)


class _Observed:
    """A read-only sequence whose every use is recorded (see :class:`_Recorder`)."""

    __slots__ = ("_check", "_real")

    def _all(self) -> tuple:
        raise NotImplementedError  # pragma: no cover

    def __len__(self) -> int:
        return len(self._all())

    def __bool__(self) -> bool:
        return len(self) > 0

    def __iter__(self) -> Iterator[Any]:
        return iter(self._all())

    def __getitem__(self, i: Any) -> Any:
        return self._all()[i]

    def __contains__(self, x: object) -> bool:
        return x in self._all()

    def __eq__(self, other: object) -> bool:
        return self._all() == (other._all() if isinstance(other, _Observed) else other)

    def __ne__(self, other: object) -> bool:
        return not self == other

    def __hash__(self) -> int:
        return hash(self._all())

    def __repr__(self) -> str:
        return repr(self._all())

    def __reversed__(self) -> Iterator[Any]:
        return reversed(self._all())

    def __add__(self, other: Any) -> Any:
        return self._all() + other

    def __radd__(self, other: Any) -> Any:
        return other + self._all()

    def __mul__(self, n: Any) -> Any:
        return self._all() * n

    __rmul__ = __mul__

    def __lt__(self, other: Any) -> bool:
        return self._all() < (other._all() if isinstance(other, _Observed) else other)  # type: ignore[no-any-return]

    def __le__(self, other: Any) -> bool:
        return self._all() <= (other._all() if isinstance(other, _Observed) else other)  # type: ignore[no-any-return]

    def __gt__(self, other: Any) -> bool:
        return self._all() > (other._all() if isinstance(other, _Observed) else other)  # type: ignore[no-any-return]

    def __ge__(self, other: Any) -> bool:
        return self._all() >= (other._all() if isinstance(other, _Observed) else other)  # type: ignore[no-any-return]

    def index(self, *args: Any) -> int:
        return self._all().index(*args)

    def count(self, x: Any) -> int:
        return self._all().count(x)


class _ObservedValidity(_validity.Validity):
    """The :class:`~desmon.deployment.validity.Validity` of a recorded check: its
    explanation is only observed where the run uses the text (see :class:`_Text`)."""

    __slots__ = ()

    def explain(self) -> str:
        return _Text(lambda: _validity.Validity.explain(self))  # type: ignore[return-value]


class _Text(_Observed):
    """An explanation a recorded run has not read yet.

    A reaction usually only carries it into an error's detail, which decides nothing;
    every use of the text (formatting, comparing, searching, any ``str`` method)
    computes it, and so observes the answers it is made of.
    """

    __slots__ = ()

    def __init__(self, make: Callable[[], str]) -> None:
        self._check, self._real = None, make

    def _all(self) -> Any:
        return self._real()

    def __str__(self) -> str:
        return self._all()  # type: ignore[no-any-return]

    def __format__(self, spec: str) -> str:
        return format(self._all(), spec)

    def __mod__(self, other: Any) -> Any:
        return self._all() % other

    def __getattr__(self, name: str) -> Any:
        return getattr(self._all(), name)


class _Acceptable(_Observed):
    """``Validity.acceptable`` of a recorded check: membership and iteration observe lazily.

    With preferences the order depends on every acceptable platform's score: iterating,
    indexing or using the whole observes them all (:meth:`_Check.rank`); membership,
    length and truth do not depend on the order and observe as without preferences."""

    __slots__ = ("_order",)

    def __init__(self, check: _Check, real: tuple[str, ...], order: list[int]) -> None:
        self._check, self._real, self._order = check, real, order

    def _all(self) -> tuple:
        check = self._check
        if check.scored is not None:
            check.rank()
        else:
            check.ok(range(len(check.parts)))
        return self._real  # type: ignore[no-any-return]

    def __len__(self) -> int:
        self._check.ok(range(len(self._check.parts)))
        return len(self._real)

    def __contains__(self, x: object) -> bool:
        names = self._check.names
        if x not in names:
            return False  # not a checked platform: the answer depends on no platform fact
        i = names.index(x)  # type: ignore[arg-type]
        self._check.ok((i,))
        return not self._check.fails[i]

    def _static(self) -> Iterator[str]:
        """The acceptable platforms in the static order, observed one by one."""
        check = self._check
        for i in self._order:
            check.ok((i,))
            if not check.fails[i]:
                yield check.names[i]

    def __iter__(self) -> Iterator[str]:
        if self._check.scored is not None:
            return iter(self._all())
        return self._static()

    def __bool__(self) -> bool:
        for _name in self._static():  # observes the platforms up to the first acceptable one
            return True
        return False

    def __getitem__(self, i: Any) -> Any:
        if isinstance(i, int) and i >= 0 and self._check.scored is None:
            for k, name in enumerate(self):  # observes the platforms up to the i-th acceptable one
                if k == i:
                    return name
            raise IndexError("tuple index out of range")
        return self._all()[i]


class _Reasons(_Observed):
    """``Validity.rejected`` or ``check_platform``'s failures: a length observes which
    platforms fail, any content the failures themselves."""

    __slots__ = ("_single",)

    def __init__(self, check: _Check, real: tuple, single: bool = False) -> None:
        self._check, self._real, self._single = check, real, single

    def _all(self) -> tuple:
        self._check.why()
        return self._real  # type: ignore[no-any-return]

    def __len__(self) -> int:
        if self._single and not self._check.first_only:
            return len(self._all())  # how many requirements one platform fails: the failures themselves
        self._check.ok(range(len(self._check.parts)))  # how many platforms fail, or whether one does
        return len(self._real)

    def __bool__(self) -> bool:
        self._check.ok(range(len(self._check.parts)))  # whether any platform fails (a valid deployment: none)
        return len(self._real) > 0


class _Ranked(_Observed):
    """``Validity.scores`` or ``.breakdown`` of a recorded check with preferences: any use
    observes every platform's score (:meth:`_Check.rank`); their length and truth are the
    acceptable platforms'."""

    __slots__ = ("_acceptable",)

    def __init__(self, check: _Check, real: tuple, acceptable: _Acceptable) -> None:
        self._check, self._real, self._acceptable = check, real, acceptable

    def _all(self) -> tuple:
        self._check.rank()
        return self._real  # type: ignore[no-any-return]

    def __len__(self) -> int:
        return len(self._acceptable)

    def __bool__(self) -> bool:
        return bool(self._acceptable)


#: modules whose functions read a state on behalf of their caller (a refusal names the caller)
_HELPERS = frozenset({"desmon.model.system", "desmon.deployment.validity", "dataclasses", "reprlib", "pprint", "copy", "copyreg", "logging"})


def _reader_allowed() -> bool:
    """Whether the code reading a guarded fact may: a requirement check the recorder is
    answering (not any code of :mod:`desmon.deployment.validity`: its public helpers
    such as ``requirement_holds`` would read unobserved), or ``dataclasses.replace``
    copying a state (the copy is guarded too)."""
    if _RECORDING.inside:
        return True
    frame = sys._getframe(2)
    return frame.f_globals.get("__name__") == "dataclasses" and frame.f_code.co_name in ("replace", "_replace")


def _refuse(what: str, platform: str) -> UnobservedRead:
    frame = sys._getframe(2)
    while frame.f_back is not None and frame.f_globals.get("__name__") in _HELPERS:
        frame = frame.f_back  # name the code that called a helper (repr, asdict, load_of...), not the helper
    caller = frame.f_globals.get("__name__")
    return UnobservedRead(
        f"{caller} read {what} of platform {platform} outside the requirement checks "
        "(desmon.deployment.validity): the table engine cannot memoise this reaction; run with --engine direct"
    )


def _guarded_field(name: str) -> property:
    slot = getattr(PlatformState, name)  # the dataclass's slot descriptor

    def read(self: PlatformState) -> Any:
        if not _reader_allowed():
            raise _refuse(f"`{name}`", self.platform.name)
        return slot.__get__(self)

    return property(read, slot.__set__)  # the constructor still sets the slot


class _Guarded(PlatformState):
    """A platform state whose facts may only be read by the requirement checks (recording).

    It hashes by identity (the recording store hands out one object per facts), and
    comparing two different ones reads their facts, so it is guarded like a field.
    """

    __slots__ = ()
    up = _guarded_field("up")  # type: ignore[assignment]
    devices = _guarded_field("devices")  # type: ignore[assignment]
    load = _guarded_field("load")  # type: ignore[assignment]
    __hash__ = object.__hash__

    def __eq__(self, other: object) -> bool:
        if self is other:
            return True
        if not _reader_allowed():
            raise _refuse("the facts (comparing states)", self.platform.name)
        return PlatformState.__eq__(self, other)


#: the QueryPort's methods (desmon.deployment.ports.QueryPort)
_QUERY_METHODS = ("deployment_information", "fixed_platform", "constraints", "platform_states", "deployed_on",
                  "active_deployments", "deployments", "perception_graph", "context")


def _query_only(store: StateStore) -> Any:
    """The recording core's Query port: the store's QueryPort methods and nothing else.

    Any other attribute of the store (its fact tuples, its helpers) would let a reaction
    read platform facts unobserved: asking for one stops the recording. One the store
    lacks raises AttributeError, as the store would. The store is held in the methods'
    closure, not in an attribute.
    """

    def forward(name: str) -> Callable[..., Any]:
        def method(self: Any, *args: Any) -> Any:
            return getattr(store, name)(*args)  # looked up per call: the store rebinds some per deployment set

        method.__name__ = name
        return method

    def refuse(self: Any, name: str) -> Any:
        if not hasattr(store, name):  # what the store itself answers (``getattr(port, name, default)`` works alike)
            raise AttributeError(f"{type(store).__name__!r} object has no attribute {name!r}")
        raise UnobservedRead(
            f"the reaction asked its Query port for `{name}`, which is not a QueryPort method: the table engine "
            "cannot know what it reads; run with --engine direct"
        )

    namespace: dict[str, Any] = {name: forward(name) for name in _QUERY_METHODS}
    namespace.update(__slots__=(), validity_memo=None, __getattr__=refuse)  # validity_memo: every check is performed
    return type("QueryOnly", (), namespace)()


class _Idle:
    inside = 1  # outside a recording nothing is guarded


_RECORDING: Any = _Idle()


class _GuardedStore(StateStore):
    state_class = _Guarded


class _NoMemo(dict):
    """A memo that never remembers (a recorded run must perform every check it makes)."""

    def __setitem__(self, key: Any, value: Any) -> None:
        pass


def table_unsupported(checker: TransitionSystem) -> str | None:
    """Why the table engine cannot run ``checker``'s search, or None."""
    if checker.symmetry is not None:
        return "symmetry reduction runs on the direct engine"
    b = checker.bounds
    where = {d.name: d.platform for d in checker.model.devices}
    for p in checker.model.platforms:
        k = sum(1 for d in b.devices if where[d] == p.name)
        digits = (2 if p.name in b.platforms or p.name in b.joins else 1) * (1 << k) * len(b.loads.get(p.name, (0,)))
        if digits > MAX_DIGITS:
            return (f"platform {p.name} has {digits:,} combinations of facts (its bounded devices, up/down and load levels); "
                    f"the table engine tabulates at most {MAX_DIGITS:,} per platform")
    return None


# ------------------------------------------------------------------------------------
# the environment code
# ------------------------------------------------------------------------------------
def _contexts(init: Key, b: Any) -> list[str | None]:
    """The contexts a search from ``init`` can reach, numbered: the initial one, then the bounds' actions."""
    ctxs: list[str | None] = [init.context]
    for a in (*b.actions, *(b.task or {}), *(x for nxt in (b.task or {}).values() for x in nxt)):
        if a not in ctxs:
            ctxs.append(a)
    return ctxs


def _variants(model: Any, changes: Sequence[RequirementChange], init: Key) -> dict[str, list[tuple]]:
    """The requirements each changed graph can have: the declared ones first, then the
    initial state's (the scenario's initial facts may change them), then every variant the
    listed changes reach from those (in order of discovery)."""
    out: dict[str, list[tuple]] = {}
    initial = dict(init.specs)
    for spec in model.specs:
        mine = [c for c in changes if c.graph == spec.graph]
        if not mine and spec.graph not in initial:
            continue
        found, i = [spec.requirements], 0
        if initial.get(spec.graph, spec.requirements) not in found:
            found.append(initial[spec.graph])
        while i < len(found):
            for c in mine:
                nxt = c.apply(found[i])
                if nxt not in found:
                    found.append(nxt)
                    if len(found) > 1 << _ROOT_CTX:
                        raise TableUnsupported(f"table engine: the requirement changes give {spec.graph} too many variants to encode; run with --engine direct")
            i += 1
        out[spec.graph] = found
    return out


class _Env:
    """Environment facts <-> one int: a context digit, a digit per changed graph (its
    current requirements), then one digit per platform (down or absent, failed devices,
    load level). The context and requirement digits together are the *global* digit
    (``env % G``): what a reaction may read besides the deployments and the platforms."""

    def __init__(self, checker: Any, init: Key) -> None:
        model, b = checker.model, checker.bounds
        self.plats = [p.name for p in model.platforms]
        self.platform_of = {d.name: d.platform for d in model.devices}
        P = len(self.plats)
        self.ctxs = _contexts(init, b)
        self.C = len(self.ctxs)
        # requirement variants: digit g of the global digit is graph g's variant number
        self.variants = _variants(model, b.requirement_changes, init)
        self.vgraphs = sorted(self.variants)
        self.declared = {s.graph: s.requirements for s in model.specs}
        self.VW: list[int] = []  # the weight of each changed graph's digit in the env code
        v = self.C
        for g in self.vgraphs:
            self.VW.append(v)
            v *= len(self.variants[g])
        self.G = v
        self.res = b.load_resource
        self.joins = frozenset(b.joins)
        self.const_failed = tuple(d for d in init.failed if d not in b.devices)
        self.const_down = tuple(p for p in init.down if p not in b.platforms and p not in self.joins)
        self.vdev: list[list[str]] = []
        self.U: list[int] = []
        self.K: list[int] = []
        self.R: list[int] = []
        self.W: list[int] = []
        self.decoded: list[list[tuple[bool, tuple[str, ...], tuple[tuple[str, float], ...]]]] = []
        w = self.G
        for name in self.plats:
            vd = [d for d in b.devices if self.platform_of[d] == name]
            U = 2 if name in b.platforms or name in self.joins else 1
            table = self._digits(name, vd, U, b, init)
            self.vdev.append(vd)
            self.U.append(U)
            self.K.append(len(vd))
            self.R.append(len(table))
            self.W.append(w)
            w *= len(table)
            self.decoded.append(table)
        self.space = w
        self.P = P
        self.failcount = [  # an absent on-demand platform is no failure
            np.array([int(dn and self.U[p] == 2 and self.plats[p] not in self.joins) + len(f) for dn, f, _l in self.decoded[p]], dtype=np.int64)
            for p in range(P)
        ]
        self.const_failures = len(self.const_failed) + len(self.const_down)

    def _digits(self, name: str, vd: list[str], U: int, b: Any, init: Key) -> list[tuple[bool, tuple[str, ...], tuple[tuple[str, float], ...]]]:
        """Platform ``name``'s facts (down, failed devices, load items) for each value of its
        digit: down bit (if it may go down), then one bit per bounded device, then the load level."""
        loaded = name in b.loads
        lv = tuple(b.loads[name]) if loaded else (0,)
        const_items = tuple((r, a) for r, a in dict(init.loads).get(name, ()) if not (loaded and r == self.res))
        table = []
        for c in range(U * (1 << len(vd)) * len(lv)):
            down_bit, rest = c % U, c // U
            mask, li = rest % (1 << len(vd)), rest // (1 << len(vd))
            down = bool(down_bit) if U == 2 else name in init.down
            failed = tuple(d for j, d in enumerate(vd) if mask >> j & 1)
            items = dict(const_items)
            if loaded and lv[li]:
                items[self.res] = lv[li]
            table.append((down, failed, tuple(sorted(items.items()))))
        return table

    def encode(self, key: Key) -> int:
        code = self.ctxs.index(key.context)
        changed = dict(key.specs)
        if any(g not in self.variants for g in changed):
            raise TableUnsupported("table engine: a state's requirements are outside the encoded variants; run with --engine direct")  # pragma: no cover
        for g, vw in zip(self.vgraphs, self.VW):
            code += self.variants[g].index(changed.get(g, self.declared[g])) * vw
        failed, down, loads = set(key.failed), set(key.down), dict(key.loads)
        if any(d not in failed for d in self.const_failed) or any(p not in down for p in self.const_down):
            raise CheckerError("table engine: a state left the encoded environment")  # pragma: no cover
        for p, name in enumerate(self.plats):
            want = (name in down, tuple(d for d in self.vdev[p] if d in failed), loads.get(name, ()))
            try:
                c = self.decoded[p].index(want)
            except ValueError:
                raise CheckerError(f"table engine: platform {name} facts {want} are outside its encoding") from None
            code += c * self.W[p]
        return code

    def specs(self, env: int) -> tuple[tuple[str, tuple], ...]:
        """The key's ``specs`` part of environment code ``env`` (changed graphs only, sorted)."""
        out = []
        for g, vw in zip(self.vgraphs, self.VW):
            v = env // vw % len(self.variants[g])
            if v:
                out.append((g, self.variants[g][v]))
        return tuple(out)

    def key(self, env: int, system: tuple) -> Key:
        ctx = self.ctxs[env % self.C]
        rest = env // self.G
        failed = list(self.const_failed)
        down = list(self.const_down)
        loads = []
        for p in range(self.P):
            dn, f, items = self.decoded[p][rest % self.R[p]]
            rest //= self.R[p]
            if dn and self.U[p] == 2:
                down.append(self.plats[p])
            failed.extend(f)
            if items:
                loads.append((self.plats[p], items))
        return Key(ctx, tuple(sorted(failed)), tuple(sorted(down)), tuple(loads), system[0], system[1],
                   self.specs(env) if self.vgraphs else ())

    def locals(self, envs: np.ndarray) -> np.ndarray:
        out = np.empty((len(envs), self.P), dtype=np.int64)
        rest = envs // self.G
        for p in range(self.P):
            out[:, p] = rest % self.R[p]
            rest = rest // self.R[p]
        return out


# ------------------------------------------------------------------------------------
# the engine
# ------------------------------------------------------------------------------------
class _Grow:
    """A numpy array with amortised appends."""

    def __init__(self, shape: tuple[int, ...], fill: int = 0) -> None:
        self.a = np.full(shape, fill, dtype=np.int64)
        self.n = 0
        self.fill = fill

    def append(self, row: Any) -> int:
        if self.n == len(self.a):
            more = np.full(self.a.shape, self.fill, dtype=np.int64)
            self.a = np.concatenate([self.a, more])
        self.a[self.n] = row
        self.n += 1
        return self.n - 1


class _Interned(list):
    """Distinct values numbered in order of first appearance: ``numbers(x)`` is x's number,
    ``numbers[i]`` the value numbered i. Past ``limit`` values the engine bows out."""

    def __init__(self, limit: int | None = None, what: str = "values") -> None:
        super().__init__()
        self._ids: dict[Any, int] = {}
        self._limit, self._what = limit, what

    def __call__(self, value: Any) -> int:
        i = self._ids.get(value)
        if i is None:
            i = self._ids[value] = len(self)
            if self._limit is not None and i >= self._limit:
                raise TableUnsupported(f"table engine: more than {self._limit:,} {self._what}; run with --engine direct")
            self.append(value)
        return i


class _Transitions(NamedTuple):
    """The enabled (state, event) pairs of a batch, state-major then in event order."""

    pos: np.ndarray  # the state's position in the batch
    env2: np.ndarray  # the environment code after the event
    ev: np.ndarray  # the event's number (:attr:`_Events.events`)
    stim: np.ndarray  # what the event changed: 0 context, 1 + platform, P + 1 nothing
    sys: np.ndarray  # the state's system part
    loc: np.ndarray  # the platform digits after the event, one row per transition
    ctx: np.ndarray  # the context digit of each state of the batch


class _Units(NamedTuple):
    """A batch's (transition, failed-start prefix) units in the direct engine's order."""

    ids: np.ndarray  # the batch's state numbers
    tr: _Transitions  # its enabled transitions
    t: np.ndarray  # each unit's transition
    pre: np.ndarray  # its failed-start prefix
    leaf: np.ndarray  # its reaction leaf
    code: np.ndarray  # the state it reaches


class _Events:
    """The bounded environment's events as numpy operations on environment codes, in
    the order of :func:`desmon.verify.environment.enabled_events`."""

    def __init__(self, engine: "TableEngine", env: _Env) -> None:
        b = engine.bounds
        self.env, self.bounds, self.P = env, b, engine.P
        self.events: _Interned = _Interned()
        C = env.C
        moves = [b.action_moves(c) for c in env.ctxs]
        kmax = max((len(m) for m in moves), default=0)
        self.move_to = np.full((C, max(kmax, 1)), -1, dtype=np.int64)
        self.move_ev = np.full((C, max(kmax, 1)), -1, dtype=np.int64)
        for c, m in enumerate(moves):
            for k, a in enumerate(m):
                self.move_to[c, k] = env.ctxs.index(a)
                self.move_ev[c, k] = self._id(ActionChange(a))
        self.slots: list[tuple] = [("action", k) for k in range(kmax)]
        for d in b.devices:
            p = engine.platform_index[env.platform_of[d]]
            self.slots.append(("device", p, env.vdev[p].index(d), self._id(DeviceFail(d)), self._id(DeviceRepair(d))))
        for name in b.platforms:
            self.slots.append(("platform", engine.platform_index[name], self._id(PlatformDown(name)), self._id(PlatformUp(name))))
        for name, lv in b.loads.items():
            ids = np.array([self._id(LoadChange(name, x, b.load_resource)) for x in lv], dtype=np.int64)
            self.slots.append(("load", engine.platform_index[name], +1, ids))
            self.slots.append(("load", engine.platform_index[name], -1, ids))
        for name in b.joins:
            self.slots.append(("join", engine.platform_index[name], self._id(PlatformJoin(name)), self._id(PlatformLeave(name))))
        for change in b.requirement_changes:
            g = env.vgraphs.index(change.graph)
            vs = env.variants[change.graph]
            to = np.array([vs.index(change.apply(r)) for r in vs], dtype=np.int64)
            self.slots.append(("requirements", g, to, self._id(change)))
        self.kind_of = np.array([_KIND_ID[event_kind(e)] for e in self.events] or [0], dtype=np.int64)

    def _id(self, e: Event) -> int:
        return self.events(e)

    def enabled(self, codes: np.ndarray) -> _Transitions:
        """The enabled transitions out of the states ``codes`` (env << SYS_BITS | system)."""
        env, b, P = self.env, self.bounds, self.P
        envs, syss = codes >> SYS_BITS, codes & _SYS_MASK
        L = env.locals(envs)
        ctx = envs % env.C
        if b.max_failures is None:
            can_fail = np.ones(len(envs), dtype=bool)
        else:
            nfail = np.full(len(envs), env.const_failures, dtype=np.int64)
            for p in range(P):
                nfail += env.failcount[p][L[:, p]]
            can_fail = nfail < b.max_failures
        S, N = len(self.slots), len(envs)
        M = np.zeros((S, N), dtype=bool)
        E2 = np.zeros((S, N), dtype=np.int64)
        EV = np.zeros((S, N), dtype=np.int64)
        ST = np.zeros((S, N), dtype=np.int64)
        for s, spec in enumerate(self.slots):
            kind = spec[0]
            if kind == "action":
                k = spec[1]
                tgt = self.move_to[ctx, k]
                M[s] = tgt >= 0
                E2[s] = envs - ctx + tgt
                EV[s] = self.move_ev[ctx, k]
                ST[s] = np.where(tgt == ctx, P + 1, 0)
            elif kind == "device":
                _k, p, j, ev_fail, ev_rep = spec
                unit = env.W[p] * env.U[p] * (1 << j)
                failed = ((L[:, p] // env.U[p] >> j) & 1).astype(bool)
                M[s] = np.where(failed, b.repair, can_fail)
                E2[s] = np.where(failed, envs - unit, envs + unit)
                EV[s] = np.where(failed, ev_rep, ev_fail)
                ST[s] = p + 1
            elif kind == "platform":
                _k, p, ev_down, ev_up = spec
                unit = env.W[p]
                down = (L[:, p] % 2).astype(bool)
                M[s] = np.where(down, b.repair, can_fail)
                E2[s] = np.where(down, envs - unit, envs + unit)
                EV[s] = np.where(down, ev_up, ev_down)
                ST[s] = p + 1
            elif kind == "join":  # always enabled: absent -> join, present -> leave
                _k, p, ev_join, ev_leave = spec
                unit = env.W[p]
                down = (L[:, p] % 2).astype(bool)
                M[s] = True
                E2[s] = np.where(down, envs - unit, envs + unit)
                EV[s] = np.where(down, ev_join, ev_leave)
                ST[s] = p + 1
            elif kind == "requirements":  # always enabled; a change that changes nothing is no stimulus
                _k, g, to, ev_id = spec
                vw = env.VW[g]
                v = envs // vw % len(to)
                w = to[v]
                M[s] = True
                E2[s] = envs + (w - v) * vw
                EV[s] = ev_id
                ST[s] = np.where(w != v, P + 3 + g, P + 1)
            else:
                _k, p, step, ids_lv = spec
                unit = env.W[p] * env.U[p] * (1 << env.K[p])
                to = L[:, p] // (env.U[p] << env.K[p]) + step
                M[s] = (to >= 0) & (to < len(ids_lv))
                E2[s] = envs + step * unit
                EV[s] = ids_lv[np.clip(to, 0, len(ids_lv) - 1)]
                ST[s] = p + 1
        pos, slot = np.nonzero(M.T)
        env2 = E2[slot, pos]
        return _Transitions(pos, env2, EV[slot, pos], ST[slot, pos], syss[pos], env.locals(env2), ctx)


class TableEngine:
    """The table engine for one :class:`~desmon.verify.system.TransitionSystem` (see the module doc)."""

    def __init__(self, checker: TransitionSystem) -> None:
        self.checker = checker
        self.model = checker.model
        self.bounds = checker.bounds
        self.platform_index = {p.name: i for i, p in enumerate(self.model.platforms)}
        # the recording twin: the same scenario, deployer, invariants and bounds, on a
        # store that hands out guarded platform states and remembers no validity answer
        rc = type(checker).__new__(type(checker))
        rc.__dict__.update(checker.__dict__)
        rc.store = _GuardedStore(self.model)
        rc.store.validity_memo = None  # type: ignore[assignment]
        rc.core = DeploymentCore(self.model, _query_only(rc.store), rc.store, checker.core.deployer)
        rc.store.watch = checker.instant
        rc.store.watch_check = rc._instant_check
        rc._instant_memo = _NoMemo()
        self.rc = rc
        self.recorder = _Recorder(self)
        self.recorder.store = rc.store
        # interning
        self._deployed = _Interned()  # deployments on one platform, as its states carry them
        self._table_args = _Interned()  # (requirements, graph) of a requirement check
        self.systems = _Interned(1 << SYS_BITS, "distinct deployment states")  # (deployments, standing)
        self.prefixes = _Interned(1 << _ROOT_PREFIX, "failed-start prefixes")
        self.prefixes(())
        # decision trees
        P = len(self.model.platforms)
        self.P = P
        self.roots: dict[int, int] = {}
        self.node_leaf = _Grow((1024,), -2)  # -2 open, -1 check node, >= 0 leaf id
        self.node_desc: list[tuple | None] = []
        self.node_base = _Grow((1024, P))
        self.node_plat = _Grow((1024, P))
        self.node_mult = _Grow((1024, P))
        self.node_len = _Grow((1024,))
        self.edges: dict[int, int] = {}
        self._ekeys = np.zeros(0, dtype=np.int64)
        self._echild = np.zeros(0, dtype=np.int64)
        self._new_edges: dict[int, int] = {}  # edges added since the arrays were last merged
        self.leaves = _Interned()
        self._leaf_sys: list[int] = []  # a reaction leaf's next system part (-1: an invariants leaf)
        self._leaf_inst: list[bool] = []  # a reaction leaf with an instantaneous violation
        self.width = 1
        self.ok = _Grow((4096,))
        self._blocks: dict[tuple, tuple[int, int]] = {}
        self._fails: dict[tuple, list[tuple]] = {}
        self._plat_states: dict[tuple[int, int], list[PlatformState]] = {}
        self._ids: dict[tuple, dict[tuple, int]] = {}
        self.records = 0  # real runs of the core (reactions and invariant checks)
        self.budget = Budget(0.0)  # the search's (set by run)

    def _go_on(self) -> None:
        """Raise :class:`_Spent` if the search must stop (time, memory, Ctrl-C)."""
        if self.budget.spent():
            raise _Spent

    # -- interning --------------------------------------------------------------------
    def intern_deployed(self, deployed: tuple) -> int:
        return self._deployed(deployed)

    def intern_table(self, reqs: tuple, graph: str | None) -> int:
        return self._table_args((reqs, graph))

    def system(self, deployments: tuple, standing: tuple) -> int:
        return self.systems((deployments, standing))

    def prefix(self, p: tuple[bool, ...]) -> int:
        return self.prefixes(p)

    def _leaf(self, value: tuple) -> int:
        n = len(self.leaves)
        i = self.leaves(value)
        if i == n:  # a new leaf
            self._leaf_sys.append(value[1] if value[0] == "r" else -1)
            self._leaf_inst.append(value[0] == "r" and value[5] is not None)
        return i

    # -- per-platform answers -----------------------------------------------------------
    def _states(self, p: int, dep: int) -> list[PlatformState]:
        """Platform ``p``'s state with deployments ``dep``, per platform digit."""
        k = (p, dep)
        out = self._plat_states.get(k)
        if out is None:
            platform = self.model.platforms[p]
            devices_on = tuple(d for d in self.model.devices if d.platform == platform.name)
            deployed = self._deployed[dep]
            out = []
            always = self.env.const_failed
            for down, failed, load in self.env.decoded[p]:
                out_of_order = set(failed).union(always)
                devices = tuple(d for d in devices_on if d.name not in out_of_order)
                out.append(PlatformState(platform, not down, devices, load, deployed))
            self._plat_states[k] = out
        return out

    def _failures(self, table: int, first_only: bool, p: int, dep: int) -> list[tuple]:
        """The failures of check ``table`` on platform ``p`` with deployments ``dep``, per platform digit."""
        k = (table, first_only, p, dep)
        out = self._fails.get(k)
        if out is None:
            reqs, graph = self._table_args[table]
            check = _validity._check_platform.__wrapped__
            out = self._fails[k] = [check(reqs, st, graph, first_only) for st in self._states(p, dep)]
        return out

    def _score_keys(self, table: int, p: int, dep: int) -> list[tuple | None]:
        """The score key (:func:`_score_key`) of check ``table`` on platform ``p`` with
        deployments ``dep`` per platform digit, None where the platform is rejected."""
        reqs, graph = self._table_args[table]
        return [None if f else _score_key(reqs, st, graph) for f, st in zip(self._failures(table, True, p, dep), self._states(p, dep))]

    def _block(self, mode: str, table: int, first_only: bool | None, p: int, dep: int) -> tuple[int, int]:
        """(offset, radix) of the answers of a check per platform digit: 1/0 for "ok", for
        "why" the failures numbered in order of first appearance."""
        k = (mode, table, first_only, p, dep)
        hit = self._blocks.get(k)
        if hit is not None:
            return hit
        off = self.ok.n
        if mode == "rank":  # 0 rejected, else 1 + the score key's number
            ids: dict[tuple | None, int] = {None: 0}
            for sk in self._score_keys(table, p, dep):
                self.ok.append(ids.setdefault(sk, len(ids)))
            self._ids[("rank", table, p, dep)] = ids
            self._blocks[k] = (off, len(ids))
            return off, len(ids)
        fails = self._failures(table, bool(first_only), p, dep)
        if mode == "ok":
            for f in fails:
                self.ok.append(0 if f else 1)
            radix = 2
        else:
            ids = {}
            for f in fails:
                self.ok.append(ids.setdefault(f, len(ids)))
            self._ids[(table, bool(first_only), p, dep)] = ids
            radix = len(ids)
        self._blocks[k] = (off, radix)
        return off, radix

    def failure_id(self, table: int, first_only: bool, p: int, dep: int, fails: tuple) -> tuple[int, int]:
        """(number, radix) of ``fails`` among the failures check ``table`` can give on ``p`` with ``dep``."""
        self._block("why", table, first_only, p, dep)
        ids = self._ids[(table, first_only, p, dep)]
        if fails not in ids:
            raise CheckerError(  # pragma: no cover - a bug in the engine, not in the system under test
                f"table engine: a recorded requirement check on {self.model.platforms[p].name} is not among its per-digit answers"
            )
        return ids[fails], len(ids)

    def score_id(self, table: int, p: int, dep: int, key: tuple | None) -> tuple[int, int]:
        """(number, radix) of score key ``key`` (None: rejected) among those check ``table``
        can give on ``p`` with ``dep``."""
        self._block("rank", table, None, p, dep)
        ids = self._ids[("rank", table, p, dep)]
        if key not in ids:
            raise CheckerError(  # pragma: no cover - a bug in the engine, not in the system under test
                f"table engine: a recorded preference score on {self.model.platforms[p].name} is not among its per-digit answers"
            )
        return ids[key], len(ids)

    # -- decision trees ---------------------------------------------------------------
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

    def _insert(self, root: int, obs: list[tuple[tuple, int]], leaf: int) -> None:
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
                    off, radix = self._block(mode, table, first_only, p, dep)
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

    def _walk(self, roots: np.ndarray, rows: np.ndarray, loc: np.ndarray, record: Callable[[int], None]) -> np.ndarray:
        """Leaf ids for units with root keys ``roots`` and platform digits ``loc[rows]``;
        ``record(unit)`` runs the real core for a unit whose answers leave the trees."""
        go_on = self._go_on  # the budget, between two recorded runs and two rounds
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
            ok = self.ok.a
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

    # -- recording ----------------------------------------------------------------------
    def _recording(self, run: Callable[[], Any], plain: Callable[[], Any]) -> tuple[Any, list[tuple[tuple, int]]]:
        """``run()`` with the observer installed: (its result, the observations).

        A ``TypeError`` or ``AttributeError`` may be the deployer's own bug or a check's
        result used as what its wrapper is not (a ``str`` for ``str.join``...): ``plain()``,
        the same run on the direct engine's store, tells them apart. Its error is the
        deployer's and is raised as it is; if it succeeds, the table engine bows out.
        """
        global _RECORDING
        rec = self.recorder
        rec.obs = []
        rec.made = set()
        rec.inside = 0
        _RECORDING, _validity._observer = rec, rec
        try:
            out = run()
        except (TypeError, AttributeError) as exc:
            _RECORDING, _validity._observer = _Idle(), None
            out = plain()  # the deployer's own error: raised here, as the direct engine would
            if isinstance(out, tuple) and len(out) == 4 and out[3] is not None and out[3][0] == CRASH:
                self.records += 1  # the deployer's own fault (the direct run fails too): its CRASH, as recorded so far
                return _PlainRun(out), rec.obs
            raise TableUnsupported(
                f"the reaction used a requirement check's result in a way the table engine cannot observe ({exc}); "
                "run with --engine direct"
            ) from exc
        finally:
            _RECORDING, _validity._observer = _Idle(), None
        self.records += 1
        return out, rec.obs

    def record_reaction(self, key: Key, event: Event, prefix: tuple[bool, ...], root: int, env2: int, stim: int) -> None:
        rc = self.rc

        def run() -> tuple:
            st = rc.store
            st.load(key)
            rc.core.standing = frozenset(key.standing)
            st.begin(prefix)
            stimulus, log = rc.step_under_guard(rc.core, st, event, recording=True)  # a fault: the instant CRASH
            instant = st.instant
            if rc.core.findings and instant is None:  # as TransitionSystem.run_one
                found = rc.core.finding(rc._checked)
                if found is not None:
                    instant = (found[0], found[1], "the reaction")
            return stimulus, log, st.key(rc.core.standing), tuple(st.outcomes), instant

        out, obs = self._recording(run, lambda: self.checker.run_one(key, event, prefix))
        if isinstance(out, _PlainRun):  # the deployer failed with a TypeError or AttributeError of its own
            nkey, outcomes, log, instant = out
            stimulus = None
        else:
            (stimulus, log, nkey, outcomes, instant) = out
            if self.records <= RECHECK_FIRST or not self.records % RECHECK_EVERY:
                self._same_commands(key, event, prefix, log)
        if stimulus is None:
            got = stim
        elif stimulus.context_changed:
            got = 0
        elif stimulus.specs_changed:
            got = self.P + 3 + self.env.vgraphs.index(stimulus.specs_changed[0])
        else:
            got = self.platform_index[stimulus.changed_platforms[0]] + 1 if stimulus.changed_platforms else self.P + 1
        expect = self.env.key(env2, (nkey.deployments, nkey.standing))
        if got != stim or expect != nkey:
            raise TableUnsupported(f"table engine: {event} on {key} gave {nkey} (stimulus {stimulus}), the encoding expected {expect}")  # pragma: no cover
        fails = tuple(i for i, ok in enumerate(outcomes) if not ok)
        names = tuple(branch_name(c, ok) for c, ok in log.commands) if log.commands else KEPT_BRANCH
        inst = instant[0] if instant is not None else None
        leaf = self._leaf(("r", self.system(nkey.deployments, nkey.standing), outcomes, fails, names, inst))
        self._insert(root, obs, leaf)

    def _same_commands(self, key: Key, event: Event, prefix: tuple[bool, ...], log: Any) -> None:
        """The recorded reaction run again on the direct engine's store: other commands are
        the deployer's nondeterminism (refused with both lists, as the direct engine does)."""
        _n, _o, again, _i = self.checker.run_one(key, event, prefix)
        if [command_key(c) for c, _ok in log.commands] != [command_key(c) for c, _ok in again.commands]:
            was, now = [str(command_key(c)[0]) for c, _ok in log.commands], [str(c) for c, _ok in again.commands]
            raise NondeterminismError(
                f"deployer {self.checker.deployer_name} is nondeterministic (not a function of what it reads through its ports): reacting twice to {event} in the same state it issued "
                f"first [{', '.join(was) or 'no command'}], then [{', '.join(now) or 'no command'}]; a reaction must be a function "
                "of its readings (no randomness, clock or state kept between calls: docs/deployers.md)"
            )

    def record_invariants(self, key: Key, root: int) -> None:
        bad, obs = self._recording(lambda: self.rc.violations(key), lambda: self.checker.violations(key))
        self._insert(root, obs, self._leaf(("v", tuple(n for n, _m in bad))))

    # -- the search ---------------------------------------------------------------------
    def key_of(self, i: int) -> Key:
        """The :class:`Key` of state number ``i``."""
        c = self.codes[i]
        return self.env.key(c >> SYS_BITS, self.systems[c & _SYS_MASK])

    def _units(self, ids: np.ndarray, tr: "_Transitions") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Every (transition, failed-start prefix) unit of a batch, resolved to its leaf, in the
        direct engine's order: by transition, then generation by generation as
        :meth:`TransitionSystem.successors <desmon.verify.system.TransitionSystem.successors>` queues the
        prefixes each run's start outcomes open. Returns (transition, prefix, leaf) arrays."""
        G, bound = self.env.G, self.bounds.start_failures
        T = len(tr.env2)
        u_t = np.arange(T, dtype=np.int64)
        u_pre = np.zeros(T, dtype=np.int64)
        u_rank = np.zeros(T, dtype=np.int64)
        parts: list[tuple[np.ndarray, ...]] = []
        gen = 0
        while len(u_t):
            roots = _root_key(tr.sys[u_t], tr.env2[u_t] % G, tr.stim[u_t], u_pre)

            def record_unit(u: int, u_t: np.ndarray = u_t, u_pre: np.ndarray = u_pre, roots: np.ndarray = roots) -> None:
                t = int(u_t[u])
                self.record_reaction(self.key_of(int(ids[tr.pos[t]])), self.events.events[int(tr.ev[t])],
                                     self.prefixes[int(u_pre[u])], int(roots[u]), int(tr.env2[t]), int(tr.stim[t]))

            leaf = self._walk(roots, u_t, tr.loc, record_unit)
            parts.append((u_t, np.full(len(u_t), gen, dtype=np.int64), u_rank, u_pre, leaf))
            if not bound:
                break
            # the failed-start prefixes each unit's start outcomes open
            n_leaves = len(self.leaves)
            pairs = u_pre * n_leaves + leaf
            up, pinv = np.unique(pairs, return_inverse=True)
            kids: list[list[int]] = []
            for pv in up.tolist():
                pre, lf = self.prefixes[pv // n_leaves], self.leaves[pv % n_leaves]
                outcomes, fails = lf[2], lf[3]
                kids.append([self.prefix(outcomes[:i] + (False,)) for i in range(len(pre), len(outcomes))] if len(fails) < bound else [])
            counts = np.array([len(k) for k in kids], dtype=np.int64)[pinv]
            if not counts.any():
                break
            order = np.lexsort((u_rank, u_t))
            order = order[counts[order] > 0]
            n_t = np.repeat(u_t[order], counts[order])
            n_pre = np.array([x for i in order.tolist() for x in kids[pinv[i]]], dtype=np.int64)
            starts = np.r_[0, np.flatnonzero(np.diff(n_t)) + 1]
            u_rank = np.arange(len(n_t)) - np.repeat(starts, np.diff(np.r_[starts, len(n_t)]))
            u_t, u_pre = n_t, n_pre
            gen += 1
        U_t, U_gen, U_rank, U_pre, U_leaf = (np.concatenate(x) for x in zip(*parts))
        order = np.lexsort((U_rank, U_gen, U_t))
        return U_t[order], U_pre[order], U_leaf[order]

    def _violated(self, cand_t: np.ndarray, cand_sys: np.ndarray, tr: "_Transitions") -> np.ndarray:
        """The invariants leaf of each candidate new state (memoised like reactions)."""
        if not len(cand_t):
            return np.zeros(0, dtype=np.int64)
        roots = _root_key(cand_sys, tr.env2[cand_t] % self.env.G, self.P + 2, 0)

        def record_state(u: int) -> None:
            t = int(cand_t[u])
            self.record_invariants(self.env.key(int(tr.env2[t]), self.systems[int(cand_sys[u])]), int(roots[u]))

        return self._walk(roots, cand_t, tr.loc, record_state)

    def run(self, res: "CheckResult", *, max_states: int | None, max_depth: int | None, keep_going: bool,
            budget: Budget) -> tuple[dict[str, Counterexample], str, int]:
        """The BFS of the direct engine (:mod:`desmon.verify.direct`), counting into ``res``;
        returns (counterexamples found, why incomplete or "", depth).

        ``budget`` (time, memory, Ctrl-C) is looked at before each batch, between two
        recorded runs of the core and two rounds of a tree walk (a batch that runs out
        there is dropped whole: nothing of it is counted yet), and every
        :data:`LOOK_EVERY` new states (the batch is then cut after the current
        transition, as ``max_states`` cuts it)."""
        self.budget, self.res, self.max_states = budget, res, max_states
        ch = self.checker
        init = ch.initial()
        env = self._encode(init)
        # states: code = env << SYS_BITS | system
        codes = self.codes = array("q", [env.encode(init) << SYS_BITS | self.system(init.deployments, init.standing)])
        trail = self.trail = Trail(ch, self.key_of, keep_going)
        self.seen = {codes[0]}
        for name, msg in ch.violations(init):
            trail.record(name, msg, 0)
        self.any_found = bool(trail.found)
        self.depth = self.transitions = 0
        self.incomplete = ""
        budget.status = lambda: (len(codes), self.transitions, self.depth)
        try:
            frontier = np.array([0], dtype=np.int64)
            while len(frontier) and not self._finished() and not self.incomplete:
                if max_depth is not None and self.depth >= max_depth:
                    self.incomplete = f"max depth {max_depth} reached with {len(frontier)} states unexplored"
                    break
                nxt = self._level(frontier)
                if nxt:
                    self.depth += 1
                frontier = np.array(nxt, dtype=np.int64)
        except KeyboardInterrupt:  # a second Ctrl-C (or one the handler could not catch)
            self.incomplete = INTERRUPTED
            trail.truncate(codes)
        except ReactionStopped as stop:  # the budget ran out inside a deployer's reaction
            self.incomplete = budget.reason or str(stop)
            trail.truncate(codes)
        res.transitions = self.transitions
        res.states = len(codes)
        budget.status = _final_status(len(codes), self.transitions, self.depth)  # (the search's closure let go)
        return trail.found, self.incomplete, self.depth

    def _encode(self, init: Key) -> _Env:
        """The environment code and the events of the search from ``init`` (or why the engine cannot run it)."""
        env = self.env = _Env(self.checker, init)
        if env.G > 1 << _ROOT_CTX or self.P + 3 + len(env.vgraphs) > 1 << _ROOT_STIM:
            raise TableUnsupported(
                f"table engine: {env.C} contexts, {env.G // env.C} combinations of requirements and {self.P} platforms do not fit "
                "its tree keys; run with --engine direct"
            )
        if env.space.bit_length() + SYS_BITS > 62:
            raise TableUnsupported(f"table engine: the environment has {env.space:,} combinations, too many to encode; run with --engine direct")
        # the answers of unused check positions: a block of zeros as long as any platform's digit range
        for _ in range(max(env.R)):
            self.ok.append(0)
        self.events = _Events(self, env)
        return env

    def _finished(self) -> bool:
        return self.any_found and self.trail.done()

    def _level(self, frontier: np.ndarray) -> list[int]:
        """One BFS level, batch by batch; returns the next level."""
        nxt: list[int] = []
        for lo in range(0, len(frontier), CHUNK_STATES):
            if self.budget.spent():
                self.incomplete = self.budget.reason
                break
            if self._batch(frontier[lo: lo + CHUNK_STATES], nxt):
                break
        return nxt

    def _batch(self, ids: np.ndarray, nxt: list[int]) -> bool:
        """Expand the states ``ids`` (one numpy batch); True if the search stops in it."""
        sc = np.frombuffer(self.codes, dtype=np.int64)[ids]
        tr = self.events.enabled(sc)
        if not len(tr.env2):  # no state of this batch enables an event
            _count(self.res.rules, self.env.ctxs, tr.ctx, self.env.C)
            return False
        try:
            U_t, U_pre, U_leaf = self._units(ids, tr)
            leaf_sys = np.array(self._leaf_sys, dtype=np.int64)
            U_code = (tr.env2[U_t] << SYS_BITS) | leaf_sys[U_leaf]
            # candidate new states: first occurrence in this batch, not seen before
            seen = self.seen
            uniq, first = np.unique(U_code, return_index=True)
            fresh = np.fromiter((c not in seen for c in uniq.tolist()), dtype=bool, count=len(uniq))
            cand = np.sort(first[fresh])
            bad_of = dict(zip(cand.tolist(), self._violated(U_t[cand], leaf_sys[U_leaf[cand]], tr).tolist()))
        except _Spent:  # between two recorded runs or walk rounds: the batch is dropped
            self.incomplete = self.budget.reason
            return True
        units = _Units(ids, tr, U_t, U_pre, U_leaf, U_code)
        cut_t, stop_unit = self._consume(units, cand, bad_of, nxt)
        self._count_batch(units, sc, cut_t, stop_unit)
        return cut_t < len(tr.env2)

    def _consume(self, units: "_Units", cand: np.ndarray, bad_of: dict[int, int], nxt: list[int]) -> tuple[int, int]:
        """The records in order, as the direct engine's search loop meets them: it stops
        after the event that found what it looked for or reached the cap, or at once when
        a repaired instantaneous violation completes the search. Returns (the last
        transition counted, the unit the search stopped at or -1)."""
        U_t, U_leaf = units.t, units.leaf
        inst_units = np.flatnonzero(np.array(self._leaf_inst, dtype=bool)[U_leaf])
        cut_t, stop_unit = len(units.tr.env2), -1
        spent = self.budget.spent
        for n_looked, u in enumerate(np.union1d(cand, inst_units).tolist(), 1):
            t = int(U_t[u])
            if t > cut_t:
                break
            if not n_looked % LOOK_EVERY and not self.incomplete and spent():
                self.incomplete, cut_t = self.budget.reason, t  # cut after this transition, as max_states does
            lf = self.leaves[int(U_leaf[u])]
            if lf[5] is not None and lf[5] not in self.trail.found and self._repaired(units, u, t, lf):
                return t, u
            if u in bad_of:
                self._new_state(units, u, t, lf, self.leaves[bad_of[u]][1], nxt)
            if self._finished() or self.incomplete:
                cut_t = t
        return cut_t, stop_unit

    def _repaired(self, units: "_Units", u: int, t: int, lf: tuple) -> bool:
        """Unit ``u`` broke instantaneous invariant ``lf[5]`` inside its reaction: if it was
        repaired before quiescence, record it (the real run gives the message). True if
        the search then has what it looks for."""
        tr = units.tr
        ch = self.checker
        nkey = self.env.key(int(tr.env2[t]), self.systems[lf[1]])
        if lf[5] in {v for v, _m in ch.violations(nkey)}:
            return False
        here = int(units.ids[tr.pos[t]])
        event = self.events.events[int(tr.ev[t])]
        _n, _o, _log, instant = ch.run_one(self.key_of(here), event, self.prefixes[int(units.pre[u])])
        self.trail.record(instant[0], instant[1], here, instant[2], (event, lf[3]))
        self.any_found = True
        return self.trail.done()

    def _new_state(self, units: "_Units", u: int, t: int, lf: tuple, bad: tuple, nxt: list[int]) -> None:
        """Unit ``u`` reached a new state: number it, label it, and record what it violates."""
        tr, ev = units.tr, self.events
        c = int(units.code[u])
        self.seen.add(c)
        codes = self.codes
        ni = len(codes)
        codes.append(c)
        e = int(tr.ev[t])
        self.trail.add(int(units.ids[tr.pos[t]]), (e, lf[3]), (ev.events[e], lf[3]))
        self.res.new_states[EVENT_KINDS[ev.kind_of[e]]] += 1
        if self.max_states is not None and len(codes) >= self.max_states:
            self.incomplete = f"max states {self.max_states:,} reached"
        if bad:
            for name, msg in self.checker.violations(self.key_of(ni)):
                self.trail.record(name, msg, ni)
            self.any_found = True
        else:
            nxt.append(ni)

    def _count_batch(self, units: "_Units", sc: np.ndarray, cut_t: int, stop_unit: int) -> None:
        """Count what the direct engine counts up to the cut."""
        res, tr, ev, env = self.res, units.tr, self.events, self.env
        U_t, U_leaf, U_code = units.t, units.leaf, units.code
        T = len(tr.env2)
        inc = np.arange(stop_unit + 1) if stop_unit >= 0 else np.flatnonzero(U_t <= cut_t)
        self.transitions += len(inc)
        leaf_counts = np.bincount(U_leaf[inc], minlength=len(self.leaves))
        for lf_id in np.flatnonzero(leaf_counts).tolist():
            n = int(leaf_counts[lf_id])
            for name in self.leaves[lf_id][4]:
                res.branches[name] += n
        moved = inc[:-1] if stop_unit >= 0 else inc  # the stopping unit is not counted as a change
        moved = moved[U_code[moved] != sc[tr.pos[U_t[moved]]]]
        _count(res.changed, EVENT_KINDS, ev.kind_of[tr.ev[U_t[moved]]], len(EVENT_KINDS))
        last_t = min(cut_t, T - 1)
        _count(res.enabled, EVENT_KINDS, ev.kind_of[tr.ev[: last_t + 1]], len(EVENT_KINDS))
        n_states = int(tr.pos[last_t]) + 1 if cut_t < T else len(units.ids)
        _count(res.rules, env.ctxs, tr.ctx[:n_states], env.C)

    def explored(self) -> "_Explored":
        return _Explored(self)

    def release(self) -> None:
        """Drop the trees, tables and states (see :meth:`Checker.release
        <desmon.verify.checker.Checker.release>`): freed now by reference counting, not
        by the cyclic collector (the recorder and the recording twin point back)."""
        self.__dict__.clear()


class _Explored(Sequence[Key]):
    """The distinct states of a table-engine run in BFS order, decoded on access."""

    def __init__(self, engine: TableEngine) -> None:
        self._e = engine

    def release(self) -> None:
        self._e.release()

    def __len__(self) -> int:
        return len(self._e.codes)

    def __getitem__(self, i: Any) -> Any:
        if isinstance(i, slice):
            return [self[j] for j in range(*i.indices(len(self)))]
        return self._e.key_of(i)

    def __iter__(self) -> Iterator[Key]:
        for i in range(len(self)):
            yield self[i]

