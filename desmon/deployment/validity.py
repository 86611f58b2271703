"""Requirement checking: the paper's ``checkValidity`` with reasons.

The semantics of every requirement kind (docs/design.md §4) lives here and nowhere else.
"""

from __future__ import annotations

import threading
from contextlib import contextmanager
from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING, Any, Callable, Iterable, Iterator, Sequence

from desmon.model.requirements import (
    PLATFORM_HAS,
    Attribute,
    DeploymentSpec,
    Capacity,
    Constraint,
    Maximum,
    Minimum,
    Option,
    Preference,
    Quantity,
    Reads,
    Requirement,
    Selection,
)
from desmon.model.system import PlatformState

if TYPE_CHECKING:
    from desmon.deployment.ports import QueryPort

#: The graph being placed, or a tuple (the graph, then graphs whose Capacity shares
#: are to be treated as freed), or None (no graph: every deployed share counts).
Placing = str | tuple[str, ...] | None

#: Results kept by the memoised pure checks (bounded, so long simulations stay flat).
_MEMO_SIZE = 1 << 16

#: An observer of every requirement check, or None (always, outside the checker's table
#: engine). While :mod:`desmon.verify.table` records one reaction it sets this to an
#: object whose ``validity(reqs, states, graph, reasons)`` and ``platform(reqs, state,
#: graph, first_only)`` answer :func:`check_validity` and :func:`check_platform` (with the
#: implementations below) and record what the reaction uses of the answers: that is how
#: the engine learns what a reaction observed of the platforms. Nothing else reads it.
_observer: Any = None

#: Are the memos of :func:`check_validity` and :func:`check_platform` used? False while
#: any :func:`unmemoised` block runs (a fleet turns them off for its run); ``_unmemoised``
#: counts those blocks, under ``_MEMO_LOCK`` (blocks of several threads may overlap).
_memoise = True
_unmemoised = 0
_MEMO_LOCK = threading.Lock()

#: Issue 16: the vectorised placement path, registered by :mod:`desmon.deployment.placement`
#: when it is imported: ``vector_validity(reqs, states, graph, reasons)`` answers what
#: :func:`_check_validity` would (a Validity) or None to leave it to the loop below.
_vector_path: Any = None

__all__ = ["Failure", "Validity", "check_validity", "check_platform", "requirement_holds", "preference_term", "platform_score", "score_breakdown", "order_platforms", "acceptable_platforms", "validity_for", "deployment_valid", "clear_memos", "unmemoised", "reads_fixed_facts", "unreadable", "spec_validity", "input_failures"]


@dataclass(frozen=True, slots=True)
class Failure:
    """One requirement that one platform does not meet, and why."""

    platform: str
    requirement: str
    reason: str

    def __str__(self) -> str:
        return f"{self.platform}: {self.requirement} fails: {self.reason}"


@dataclass(frozen=True, slots=True)
class Validity:
    """Result of :func:`check_validity`: acceptable platforms (best first) and every
    failure of every rejected platform.

    With preferences, ``scores`` holds each acceptable platform's score (aligned with
    ``acceptable``) and, when reasons were asked for, ``breakdown`` each one's weighted
    terms per preference; both are empty without preferences.
    """

    acceptable: tuple[str, ...]
    rejected: tuple[tuple[str, tuple[Failure, ...]], ...]
    scores: tuple[float, ...] = ()
    breakdown: tuple[tuple[str, tuple[tuple[str, float], ...]], ...] = ()

    def failures(self, platform: str) -> tuple[Failure, ...]:
        for name, fails in self.rejected:
            if name == platform:
                return fails
        return ()

    def score(self, platform: str) -> float:
        """The preference score of an acceptable ``platform`` (0 without preferences)."""
        if not self.scores:
            return 0.0
        return self.scores[self.acceptable.index(platform)]

    def gain(self, platform: str) -> float:
        """How much the best acceptable platform scores above ``platform`` (0 if it is the best)."""
        if not self.scores or not self.acceptable:
            return 0.0
        return self.scores[0] - self.score(platform)

    def explain(self) -> str:
        lines = [f"acceptable: {', '.join(self.acceptable) or '(none)'}"]
        for name, terms in self.breakdown:
            parts = " + ".join(f"{what} {value:.3g}" for what, value in terms)
            lines.append(f"score {name}: {sum(v for _w, v in terms):.3g} = {parts}")
        for _name, fails in self.rejected:
            lines.extend(str(f) for f in fails)
        return "\n".join(lines)


def _option_holds(option: Option, state: PlatformState) -> bool:
    if option.attribute is not None:
        return str(state.platform.attribute(option.attribute)) == str(option.value)
    return any(d.matches(option.device_kind or "", option.vendor) for d in state.devices)


def _fmt(x: float) -> str:
    return f"{x:g}"


def _quantity(req: Quantity, state: PlatformState, graph: Placing) -> str | None:
    have = sum(1 for d in state.devices if d.kind == req.device_kind)
    if have >= req.count:
        return None
    return f"{have} working {req.device_kind} device(s), needs {req.count}"


def _others_using(resource: str, state: PlatformState, graph: Placing) -> list[tuple[str, float]]:
    """Shares of ``resource`` held by graphs other than the one being placed (and, for a
    tuple ``graph``, other than the graphs a placement would free)."""
    if graph is None or type(graph) is str:
        return state.used_by(resource, excluding=graph)  # type: ignore[arg-type]
    return [(g, a) for g, a in state.used_by(resource) if g not in graph]


def _capacity(req: Capacity, state: PlatformState, graph: Placing) -> str | None:
    cap = state.platform.capacity(req.resource)
    if cap is None:
        return f"has no {req.resource} capacity"
    others = _others_using(req.resource, state, graph)
    load = state.load_of(req.resource)
    free = cap - sum(a for _g, a in others) - load
    if free >= req.amount:
        return None
    unit = " MB" if req.resource == "memory" else ""
    parts = [f"capacity {_fmt(cap)}"]
    parts += [f"used by {g} {_fmt(a)}" for g, a in others]
    parts.append(f"load {_fmt(load)}")
    return f"{_fmt(free)}{unit} free ({', '.join(parts)})"


def _minimum(req: Minimum, state: PlatformState, graph: Placing) -> str | None:
    value = state.platform.prop(req.prop)
    if value is None:
        return f"has no property {req.prop!r}"
    return None if value >= req.value else f"{req.prop} is {_fmt(value)}"


def _maximum(req: Maximum, state: PlatformState, graph: Placing) -> str | None:
    value = state.platform.prop(req.prop)
    if value is None:
        return f"has no property {req.prop!r}"
    return None if value <= req.value else f"{req.prop} is {_fmt(value)}"


def _attribute(req: Attribute, state: PlatformState, graph: Placing) -> str | None:
    if req.name == PLATFORM_HAS:
        if any(d.kind == req.value for d in state.devices):
            return None
        return f"no working {req.value} attached"
    actual = state.platform.attribute(req.name)
    if actual is not None and str(actual) == str(req.value):
        return None
    return f"{req.name} is {actual!r}" if actual is not None else f"has no attribute {req.name!r}"


def _selection(req: Selection, state: PlatformState, graph: Placing) -> str | None:
    held = [o for o in req.options if _option_holds(o, state)]
    if len(held) >= req.at_least:
        return None
    have = [o.describe() for o in held]
    return f"{len(have)} of the options available ({', '.join(have) or 'none'}), needs {req.at_least}"


def _reads(req: Reads, state: PlatformState, graph: Placing) -> str | None:
    """The platform's own half of :class:`Reads`: on a platform hosting devices of the
    kind the graph reads those, so one of them must work there (the other half,
    elsewhere, is :func:`unreadable`)."""
    name = state.platform.name
    if name not in req.hosts or any(d.kind == req.kind for d in state.devices):
        return None
    own = ", ".join(d for d, p in req.devices if p == name)
    return f"{own} on {name} failed"


def _soft(req: Preference, state: PlatformState, graph: Placing) -> str | None:
    return None  # a preference never rejects a platform: it scores it (preference_term)


#: The semantics of each requirement kind, one function per kind.
_HOLDS: dict[type, Any] = {
    Quantity: _quantity,
    Capacity: _capacity,
    Minimum: _minimum,
    Maximum: _maximum,
    Attribute: _attribute,
    Selection: _selection,
    Reads: _reads,
    Preference: _soft,
}


def requirement_holds(req: Constraint, state: PlatformState, graph: Placing) -> str | None:
    """``None`` if ``req`` holds on ``state`` for ``graph``, else the reason it fails
    (a preference always holds)."""
    holds = _HOLDS.get(type(req))
    if holds is None:
        raise TypeError(f"not a requirement: {req!r}")
    return holds(req, state, graph)  # type: ignore[no-any-return]


def _free_fraction(resource: str, state: PlatformState, graph: Placing) -> float:
    cap = state.platform.capacity(resource)
    if not cap:
        return 0.0
    free = cap - sum(a for _g, a in _others_using(resource, state, graph)) - state.load_of(resource)
    return min(1.0, max(0.0, free / cap))


def preference_term(pref: Preference, state: PlatformState, graph: Placing) -> float:
    """The term in [0, 1] that ``pref`` gives ``state`` for placing ``graph`` (see
    :class:`~desmon.model.requirements.Preference`); the score adds ``weight`` times it."""
    kind, args = pref.kind, pref.args
    if kind == "vendor":
        return 1.0 if any(d.matches(args[0], args[1]) for d in state.devices) else 0.0
    if kind == "attribute":
        actual = state.platform.attribute(args[0])
        return 1.0 if actual is not None and str(actual) == args[1] else 0.0
    if kind == "most_free":
        return _free_fraction(args[0], state, graph)
    if kind == "least_loaded":
        cap = state.platform.capacity(args[0])
        return min(1.0, max(0.0, 1.0 - state.load_of(args[0]) / cap)) if cap else 0.0
    mine = graph if graph is None or type(graph) is str else graph[0]
    others = [g for g, _use in state.deployed if g != mine]
    if kind == "colocate":
        return 1.0 if any(g in args for g in others) else 0.0
    return 1.0 / (1 + len(others))  # spread


def score_breakdown(reqs: Iterable[Constraint], state: PlatformState, graph: Placing) -> tuple[tuple[str, float], ...]:
    """Each preference's weighted term for ``state`` (what ``desmon explain`` shows)."""
    return tuple((p.describe(), p.weight * preference_term(p, state, graph)) for p in reqs if isinstance(p, Preference))


def platform_score(reqs: Iterable[Constraint], state: PlatformState, graph: Placing) -> float:
    """The preference score of ``state``: the sum of weight x term (0 without preferences)."""
    return sum(p.weight * preference_term(p, state, graph) for p in reqs if isinstance(p, Preference))


_DOWN = "platform is down"
_ABSENT = "platform is not there (on demand: not joined, left, or down)"


def check_platform(
    requirements: Iterable[Requirement], state: PlatformState, graph: Placing, *, first_only: bool = False
) -> tuple[Failure, ...]:
    """Every requirement ``state`` fails for ``graph`` (only the first if ``first_only``);
    a down platform fails them all. Memoised: it is pure and the deployer, the invariants
    and the checker ask it again and again about the same facts."""
    reqs = requirements if type(requirements) is tuple else tuple(requirements)
    if _observer is not None:
        return _observer.platform(reqs, state, graph, first_only)  # type: ignore[no-any-return]
    if not _memoise:
        return _check_platform.__wrapped__(reqs, state, graph, first_only)  # type: ignore[arg-type]
    return _check_platform(reqs, state, graph, first_only)  # type: ignore[arg-type]


@lru_cache(maxsize=_MEMO_SIZE)
def _check_platform(
    requirements: tuple[Requirement, ...], state: PlatformState, graph: Placing, first_only: bool
) -> tuple[Failure, ...]:
    return _failures(_checks(requirements), state, graph, first_only, {})


def reads_fixed_facts(req: Constraint) -> bool:
    """Does ``req`` read only a platform's fixed facts (properties, attributes), never
    its run-time ones (devices, load, deployments)? Its answer for a platform then
    never changes."""
    if isinstance(req, (Maximum, Minimum)):
        return True
    if isinstance(req, Attribute):
        return req.name != PLATFORM_HAS
    if isinstance(req, Selection):
        return all(o.attribute is not None for o in req.options)
    return False


def _checks(requirements: tuple[Requirement, ...]) -> list[tuple[Any, Requirement]]:
    """Each requirement with the function of its kind (:data:`_HOLDS`), looked up once."""
    out = []
    for req in requirements:
        holds = _HOLDS.get(type(req))
        if holds is None:
            raise TypeError(f"not a requirement: {req!r}")
        if holds is not _soft:  # a preference never rejects a platform
            out.append((holds, req))
    return out


def _failures(
    checks: list[tuple[Any, Requirement]], state: PlatformState, graph: Placing, first_only: bool, texts: dict[int, str]
) -> tuple[Failure, ...]:
    """What :func:`check_platform` answers, given :func:`_checks`; ``texts`` keeps each
    requirement's description (by position) across the platforms of one question."""
    if not state.up:
        return (Failure(state.name, "platform up", _ABSENT if state.platform.on_demand else _DOWN),)
    out = []
    for k, (holds, req) in enumerate(checks):
        reason = holds(req, state, graph)
        if reason is not None:
            text = texts.get(k)
            if text is None:
                text = texts[k] = req.describe()
            out.append(Failure(state.name, text, reason))
            if first_only:
                break
    return tuple(out)


@lru_cache(maxsize=256)
def _has(kind: str) -> tuple[Attribute, ...]:
    return (Attribute(PLATFORM_HAS, kind),)


def unreadable(req: Reads, state_of: "Callable[[str], PlatformState | None]", graph: Placing, *, reasons: bool = True) -> str | None:
    """Why no device of ``req.kind`` is readable anywhere on the robot (None if one is).

    A device is readable while it works and its platform is up. This is the half of
    :class:`Reads` that a platform hosting none of the devices depends on: the graph
    then reads any of them, on the other platforms. ``state_of`` gives a platform's
    facts (None: not in the model's view). Each hosting platform is asked through
    :func:`check_platform`, so the checker's table engine observes exactly the hosts it
    reads; the text (only with ``reasons``) names each device and why it cannot be read.
    """
    place = graph if graph is None or type(graph) is str else graph[0]
    hosts = req.hosts
    seen: list[tuple[str, PlatformState | None]] = []
    for h in hosts:
        st = state_of(h)
        if st is not None and not check_platform(_has(req.kind), st, place):
            return None
        seen.append((h, st))
    if not reasons:
        return f"no readable {req.kind}"
    parts = []
    for h, st in seen:
        names = ", ".join(d for d, p in req.devices if p == h)
        if st is None:
            parts.append(f"{names} on {h}: platform unknown")
            continue
        first = check_platform(_has(req.kind), st, place)[0]
        status = "failed" if first.requirement != "platform up" else ("is not there" if first.reason == _ABSENT else "is down")
        parts.append(f"{names} on {h} {status}")
    return "; ".join(parts)


def input_failures(reads: tuple[Reads, ...], platform: str, state_of: "Callable[[str], PlatformState | None]", graph: Placing, *, reasons: bool = True) -> tuple[Failure, ...]:
    """The failures of the remote half of ``reads`` for a graph on ``platform``: each
    kind ``platform`` hosts no device of and no platform can give (the platform's own
    half is checked with its requirements: :class:`Reads` in :func:`check_platform`)."""
    out = []
    for r in reads:
        if platform not in r.hosts:
            why = unreadable(r, state_of, graph, reasons=reasons)
            if why is not None:
                out.append(Failure(platform, r.describe(), why))
                if not reasons:
                    break
    return tuple(out)


def _lookup(states: Sequence[PlatformState]) -> "Callable[[str], PlatformState | None]":
    by_name = {s.platform.name: s for s in states}
    return by_name.get


def spec_validity(
    reqs: tuple[Requirement, ...],
    reads: tuple[Reads, ...],
    states: Sequence[PlatformState],
    world: Sequence[PlatformState],
    graph: Placing,
    *,
    reasons: bool = True,
) -> Validity:
    """:func:`check_validity` of ``reqs`` and what the graph's inputs require (``reads``)
    over the candidate ``states``, reading remote inputs from ``world`` (every platform).

    A :class:`Reads` whose kind no platform of ``world`` can give rejects every
    candidate, each with the reason :func:`unreadable` gives (the hosts' devices failed
    or their platforms are down); the other requirements are then not asked, so a
    search reads no more than that (:func:`acceptable_platforms`, the question of
    ``desmon explain``, adds every other failing requirement). Otherwise the answer is
    :func:`check_validity`'s, so the checker's table engine observes it as lazily as
    any requirement check.
    """
    if not reads:
        return check_validity(reqs, states, graph, reasons=reasons)
    validity = check_validity(tuple(reqs) + reads, states, graph, reasons=reasons)
    state_of = _lookup(world)
    dead = [(r, why) for r in reads if (why := unreadable(r, state_of, graph, reasons=reasons)) is not None]
    if not dead:
        return validity
    rejected = []
    for st in order_platforms(states):
        name = st.platform.name
        fails = tuple(Failure(name, r.describe(), why) for r, why in dead)
        rejected.append((name, fails if reasons else fails[:1]))
    return Validity((), tuple(rejected))


def clear_memos() -> None:
    """Forget every memoised validity result (tests; memory)."""
    _check_platform.cache_clear()
    _check_validity.cache_clear()


@contextmanager
def unmemoised() -> Iterator[None]:
    """Within it, :func:`check_validity` and :func:`check_platform` compute every answer
    afresh (same answers, no memo). For runs whose facts seldom recur -- a fleet, where
    some platform changed between almost any two questions, so almost no answer came
    from a memo -- the memos cost hashing on every call and hold old platform states
    alive: a third of the 8-hour fleet's peak memory. The checker keeps them (its
    states recur by construction). Process-wide while any such block runs: blocks nest
    and may overlap across threads (the memos come back when the last one ends)."""
    global _memoise, _unmemoised
    with _MEMO_LOCK:
        _unmemoised += 1
        _memoise = False
    try:
        yield
    finally:
        with _MEMO_LOCK:
            _unmemoised -= 1
            _memoise = _unmemoised == 0


def order_platforms(states: Sequence[PlatformState]) -> list[PlatformState]:
    """Deterministic preference order: higher ``preference`` first, then declaration order."""
    return sorted(states, key=lambda s: -s.platform.preference)  # sorted() is stable


def check_validity(
    requirements: Iterable[Requirement],
    states: Sequence[PlatformState],
    graph: Placing = None,
    *,
    reasons: bool = True,
) -> Validity:
    """The platforms among ``states`` that meet every requirement, for deploying ``graph``.

    ``graph`` matters for Capacity: its own share never counts against it. A tuple of
    graph names asks the same for a placement that would first free the others (the
    corrected deployer's upgrade back to a preferred alternative: "acceptable if the
    running fallbacks were stopped"); none of their shares counts. Acceptable
    platforms come in preference order (see :func:`order_platforms`); rejected ones
    carry every failing requirement with a readable reason (only the first one when
    ``reasons`` is False, the fast path of the deployer). Results are memoised (pure;
    see :func:`unmemoised`).
    """
    reqs = requirements if type(requirements) is tuple else tuple(requirements)
    if _observer is not None:
        return _observer.validity(reqs, states if type(states) is tuple else tuple(states), graph, reasons)  # type: ignore[no-any-return]
    check = _check_validity if _memoise else _check_validity.__wrapped__
    return check(reqs, states if type(states) is tuple else tuple(states), graph, reasons)  # type: ignore[arg-type,no-any-return]


@lru_cache(maxsize=_MEMO_SIZE)
def _check_validity(
    reqs: tuple[Requirement, ...], states: tuple[PlatformState, ...], graph: Placing, reasons: bool
) -> Validity:
    if _vector_path is not None and _observer is None:  # issue 16: columns for large fleets
        fast = _vector_path(reqs, states, graph, reasons)
        if fast is not None:
            return fast  # type: ignore[no-any-return]
    acceptable: list[PlatformState] = []
    rejected: list[tuple[str, tuple[Failure, ...]]] = []
    checks = _checks(reqs)  # memoised as a whole here; per pair only in check_platform
    texts: dict[int, str] = {}
    first_only = not reasons
    for state in order_platforms(states):
        fails = _failures(checks, state, graph, first_only, texts)
        if fails:
            rejected.append((state.name, fails))
        else:
            acceptable.append(state)
    if not any(type(r) is Preference for r in reqs):
        return Validity(tuple(s.name for s in acceptable), tuple(rejected))
    scored = sorted(((platform_score(reqs, s, graph), s) for s in acceptable), key=lambda x: -x[0])  # stable
    breakdown = tuple((s.name, score_breakdown(reqs, s, graph)) for _v, s in scored) if reasons else ()
    return Validity(tuple(s.name for _v, s in scored), tuple(rejected), tuple(v for v, _s in scored), breakdown)


def validity_for(q: "QueryPort", spec: DeploymentSpec, *, reasons: bool = True) -> Validity:
    """check_validity for ``spec`` on the repository's current facts; a fixed deployment
    considers only its EXECUTABLE_ON platform.

    Fast path: a port whose :meth:`platform_states` hands out the *same* tuple object
    for the same facts (the checker's :class:`~desmon.verify.state.StateStore`) may
    carry a ``validity_memo`` dict. The answer is then memoised per port on the
    identities of that states tuple and of ``spec``: the entry holds both objects, so
    their ids cannot be reused while it exists, and a hit is confirmed with ``is``.
    This skips hashing the states and requirements (Python-level ``__hash__`` calls)
    that the :func:`check_validity` memo needs. The memo is cleared when it holds
    more than :data:`_MEMO_SIZE` entries. A port without the attribute (the networkx
    repository, whose states are rebuilt on every call) takes the plain path.
    """
    states = q.platform_states()
    memo: dict[tuple[int, int, bool], tuple[tuple[PlatformState, ...], DeploymentSpec, Validity]] | None = getattr(
        q, "validity_memo", None
    )
    if memo is not None:
        mk = (id(states), id(spec), reasons)
        hit = memo.get(mk)
        if hit is not None and hit[0] is states and hit[1] is spec:
            return hit[2]
    all_states = states
    fixed = q.fixed_platform(spec)
    if fixed is not None:
        states = tuple(s for s in states if s.name == fixed)
    validity = spec_validity(q.constraints(spec), spec.reads, states, all_states, spec.graph, reasons=reasons)
    if memo is not None:
        if len(memo) > _MEMO_SIZE:
            memo.clear()
        memo[mk] = (all_states, spec, validity)
    return validity


def acceptable_platforms(q: "QueryPort", graph: str) -> Validity:
    """The named query "acceptable platforms of ``graph``" with reasons (``desmon explain``)."""
    from desmon.errors import QueryError

    spec = q.deployment_information(graph)
    if spec is None:
        raise QueryError(f"no deployment information for perception graph {graph!r}: add a deployment specification")
    validity = validity_for(q, spec)
    if validity.acceptable or not spec.reads:
        return validity
    # no input readable anywhere: list every other failing requirement too (the search's
    # answer stops at the unreadable input; a person asking wants the whole picture)
    states = q.platform_states()
    fixed = q.fixed_platform(spec)
    if fixed is not None:
        states = tuple(s for s in states if s.name == fixed)
    others = check_validity(tuple(q.constraints(spec)) + spec.reads, states, spec.graph)
    merged = tuple((name, tuple(others.failures(name)) + tuple(f for f in fails if f not in others.failures(name))) for name, fails in validity.rejected)
    return Validity((), merged)


def deployment_valid(spec: DeploymentSpec | None, state: PlatformState, states: Sequence[PlatformState]) -> tuple[Failure, ...]:
    """Why an active deployment of ``spec`` on ``state`` is invalid (empty if it is valid);
    ``states`` are every platform's facts (where remote inputs are read).

    Used by the corrected deployer's bookkeeping and by the invariants alike: up, on its
    EXECUTABLE_ON platform if fixed, every requirement met (own Capacity share excluded),
    and every device kind the graph reads readable (:class:`Reads`).
    """
    if spec is None:
        return (Failure(state.name, "deployment information", "missing"),)
    if spec.fixed_platform is not None and spec.fixed_platform != state.name:
        return (Failure(state.name, f"EXECUTABLE_ON {spec.fixed_platform}", "runs on another platform"),)
    reads = spec.reads
    if not reads:
        return check_platform(spec.requirements, state, spec.graph)
    fails = check_platform(spec.requirements + reads, state, spec.graph)
    if fails:
        return fails
    return input_failures(reads, state.platform.name, _lookup(states), spec.graph)
