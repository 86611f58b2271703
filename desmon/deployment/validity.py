"""Requirement checking: the paper's ``checkValidity`` with reasons.

The semantics of every requirement kind (docs/design.md §4) lives in the kind's class
(:meth:`~desmon.model.kinds.Constraint.holds`, in :mod:`desmon.model.requirements`); this
module asks it about platforms, with reasons, memoised.
"""

from __future__ import annotations

from functools import lru_cache
from typing import TYPE_CHECKING, Any, Callable, Iterable, Sequence

from desmon.model.kinds import Placing, others_using  # Placing: the graph being placed (re-exported)
from desmon.model.requirements import PLATFORM_HAS, Attribute, Constraint, DeploymentSpec, Preference, Reads, Requirement
from desmon.model.system import PlatformState

from desmon.deployment.memo import MemoChecks, kept
from desmon.deployment.ports import SCORE_DIGITS, Failure, PlatformHandle, Validity  # Failure, Validity: the Checks port's answers (re-exported)

if TYPE_CHECKING:
    from desmon.deployment.ports import ChecksPort, QueryPort

#: Results kept by the memoised pure checks (bounded, so long simulations stay flat).
_MEMO_SIZE = 1 << 16

#: Requirement tuples :class:`PlatformMemoChecks` knows by identity before it forgets them.
_TUPLES = 1 << 12

#: What :class:`PlatformMemoChecks` derives once per question's requirements: the ids of
#: their objects, each hard one with its kind's ``holds`` (:func:`_checks`), and whether
#: one is a preference, and each hard one's description by its position in those checks
#: (filled as failures are reported: a requirement object describes itself alike each time).
_Question = tuple[tuple[int, ...], list[tuple[Any, "Requirement"]], bool, dict[int, str]]

__all__ = ["Failure", "Validity", "check_validity", "check_platform", "requirement_holds", "preference_term", "platform_score", "score_breakdown", "score_keys", "is_ranked", "order_platforms", "acceptable_platforms", "validity_for", "deployment_valid", "clear_memos", "ScalarChecks", "PlatformMemoChecks", "DEFAULT_CHECKS", "checks_for", "reads_fixed_facts", "unreadable", "spec_validity", "input_failures"]


def requirement_holds(req: Constraint, state: PlatformState, graph: Placing) -> str | None:
    """``None`` if ``req`` holds on ``state`` for ``graph``, else the reason it fails
    (a preference always holds): the kind's own :meth:`~desmon.model.kinds.Constraint.holds`."""
    if not isinstance(req, Constraint):
        raise TypeError(f"not a requirement: {req!r}")
    return req.holds(state, graph)


def _free_fraction(resource: str, state: PlatformState, graph: Placing) -> float:
    cap = state.platform.capacity(resource)
    if not cap:
        return 0.0
    free = cap - sum(a for _g, a in others_using(resource, state, graph)) - state.load_of(resource)
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
    """The preference score of ``state``: the sum of weight x term (0 without preferences), to
    :data:`~desmon.deployment.ports.SCORE_DIGITS` decimals (scores the user's numbers make
    equal tie, whatever the order the terms were added in)."""
    return round(sum(p.weight * preference_term(p, state, graph) for p in reqs if isinstance(p, Preference)), SCORE_DIGITS)


def score_keys(reqs: tuple, graph: Placing, failures: Sequence[tuple], states: Sequence[PlatformState]) -> list[tuple | None]:
    """What the preferences make of each platform: None where it is rejected (it has
    ``failures``), else its score and the weighted terms it is the sum of (what
    ``Validity.breakdown`` shows)."""
    return [None if f else (platform_score(reqs, st, graph), score_breakdown(reqs, st, graph)) for f, st in zip(failures, states)]


_DOWN = "platform is down"
_ABSENT = "platform is not there (on demand: not joined, left, or down)"


def check_platform(
    requirements: Iterable[Requirement], state: PlatformState, graph: Placing, *, first_only: bool = False,
    checks: "ChecksPort | None" = None,
) -> tuple[Failure, ...]:
    """Every requirement ``state`` fails for ``graph`` (only the first if ``first_only``);
    a down platform fails them all. Asked of ``checks`` (by default :func:`checks_for`
    the state: the scalar checks, or the recording checks a handle came from)."""
    reqs = requirements if type(requirements) is tuple else tuple(requirements)
    if checks is None:
        checks = checks_for((state,))
    return checks.platform(reqs, state, graph, first_only)


def platform_failures(
    requirements: tuple[Requirement, ...], state: PlatformState, graph: Placing, first_only: bool
) -> tuple[Failure, ...]:
    """What :func:`check_platform` answers, computed (no memo, no port): the semantics."""
    return _failures(_checks(requirements), state, graph, first_only, {})


def reads_fixed_facts(req: Constraint) -> bool:
    """Does ``req`` read only a platform's fixed facts (properties, attributes), never
    its run-time ones (devices, load, deployments)? Its answer for a platform then
    never changes (the kind's own :meth:`~desmon.model.kinds.Constraint.reads_fixed_facts`)."""
    return req.reads_fixed_facts()


def _checks(requirements: tuple[Requirement, ...]) -> list[tuple[Any, Requirement]]:
    """Each hard requirement with the ``holds`` of its kind, looked up once (a preference
    never rejects a platform)."""
    out = []
    for req in requirements:
        if not isinstance(req, Constraint):
            raise TypeError(f"not a requirement: {req!r}")
        if not req.soft:
            out.append((type(req).holds, req))
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


def unreadable(
    req: Reads, state_of: "Callable[[str], PlatformState | None]", graph: Placing, *, reasons: bool = True, checks: "ChecksPort | None" = None
) -> str | None:
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
        if st is not None and not check_platform(_has(req.kind), st, place, checks=checks):
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
        first = check_platform(_has(req.kind), st, place, checks=checks)[0]
        status = "failed" if first.requirement != "platform up" else ("is not there" if first.reason == _ABSENT else "is down")
        parts.append(f"{names} on {h} {status}")
    return "; ".join(parts)


def input_failures(
    reads: tuple[Reads, ...], platform: str, state_of: "Callable[[str], PlatformState | None]", graph: Placing, *,
    reasons: bool = True, checks: "ChecksPort | None" = None,
) -> tuple[Failure, ...]:
    """The failures of the remote half of ``reads`` for a graph on ``platform``: each
    kind ``platform`` hosts no device of and no platform can give (the platform's own
    half is checked with its requirements: :class:`Reads` in :func:`check_platform`)."""
    out = []
    for r in reads:
        if platform not in r.hosts:
            why = unreadable(r, state_of, graph, reasons=reasons, checks=checks)
            if why is not None:
                out.append(Failure(platform, r.describe(), why))
                if not reasons:
                    break
    return tuple(out)


def _lookup(states: Sequence[PlatformState]) -> "Callable[[str], PlatformState | None]":
    by_name = {s.platform.name: s for s in states}
    return by_name.get


def _joined(reqs: Sequence[Requirement], reads: tuple[Reads, ...], checks: "ChecksPort") -> tuple[Requirement, ...]:
    """``tuple(reqs) + reads``: one tuple object per question when ``checks`` keep a run's
    memos (:meth:`~desmon.deployment.memo.MemoChecks.joined`), which the Checks ports
    find again by identity; a fresh one otherwise."""
    if type(checks) is MemoChecks:
        return checks.joined(reqs, reads)  # type: ignore[no-any-return]
    return tuple(reqs) + reads


def spec_validity(
    reqs: tuple[Requirement, ...],
    reads: tuple[Reads, ...],
    states: Sequence[PlatformState],
    world: Sequence[PlatformState],
    graph: Placing,
    *,
    reasons: bool = True,
    checks: "ChecksPort | None" = None,
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
        return check_validity(reqs, states, graph, reasons=reasons, checks=checks)
    if checks is None:
        checks = checks_for(states)
    validity = check_validity(_joined(reqs, reads, checks), states, graph, reasons=reasons, checks=checks)
    state_of = _lookup(world)
    dead = [(r, why) for r in reads if (why := unreadable(r, state_of, graph, reasons=reasons, checks=checks)) is not None]
    if not dead:
        return validity
    rejected = []
    for st in order_platforms(states):
        name = st.platform.name
        fails = tuple(Failure(name, r.describe(), why) for r, why in dead)
        rejected.append((name, fails if reasons else fails[:1]))
    return Validity((), tuple(rejected))


def order_platforms(states: Sequence[PlatformState]) -> list[PlatformState]:
    """Deterministic preference order: higher ``preference`` first, then declaration order."""
    return sorted(states, key=lambda s: -s.platform.preference)  # sorted() is stable


def check_validity(
    requirements: Iterable[Requirement],
    states: Sequence[PlatformState],
    graph: Placing = None,
    *,
    reasons: bool = True,
    checks: "ChecksPort | None" = None,
) -> Validity:
    """The platforms among ``states`` that meet every requirement, for deploying ``graph``.

    ``graph`` matters for Capacity: its own share never counts against it. A tuple of
    graph names asks the same for a placement that would first free the others (the
    corrected deployer's upgrade back to a preferred alternative: "acceptable if the
    running fallbacks were stopped"); none of their shares counts. Acceptable
    platforms come in preference order (see :func:`order_platforms`); rejected ones
    carry every failing requirement with a readable reason (only the first one when
    ``reasons`` is False, the fast path of the deployer). Asked of ``checks`` (by
    default :func:`checks_for` the states).
    """
    reqs = requirements if type(requirements) is tuple else tuple(requirements)
    states = states if type(states) is tuple else tuple(states)
    if checks is None:
        checks = checks_for(states)
    return checks.validity(reqs, states, graph, reasons)


def loop_validity(reqs: tuple[Requirement, ...], states: tuple[PlatformState, ...], graph: Placing, reasons: bool) -> Validity:
    """What :func:`check_validity` answers, computed platform by platform (no memo, no
    port): the semantics every implementation of the Checks port agrees with."""
    checks = _checks(reqs)  # looked up once for every platform
    texts: dict[int, str] = {}
    first_only = not reasons
    ordered = order_platforms(states)
    return _assemble(
        reqs, ordered, [_failures(checks, state, graph, first_only, texts) for state in ordered], graph, reasons,
        lambda state: platform_score(reqs, state, graph),
    )


def _assemble(
    reqs: tuple[Requirement, ...],
    ordered: Sequence[PlatformState],
    failures: Sequence[tuple[Failure, ...]],
    graph: Placing,
    reasons: bool,
    score: Callable[[PlatformState], float],
    ranked: bool | None = None,
) -> Validity:
    """The :class:`Validity` of the platforms in ``ordered`` (:func:`order_platforms`), given
    each one's ``failures`` (aligned with ``ordered``) and preference ``score``; ``ranked``
    says whether ``reqs`` holds a preference (None: look). The one body of
    :func:`loop_validity` and of the memoised :meth:`PlatformMemoChecks.compute`."""
    acceptable: list[PlatformState] = []
    rejected: list[tuple[str, tuple[Failure, ...]]] = []
    for state, fails in zip(ordered, failures):
        if fails:
            rejected.append((state.name, fails))
        else:
            acceptable.append(state)
    if ranked is None:
        ranked = is_ranked(reqs)
    if not ranked:
        return Validity(tuple([s.name for s in acceptable]), tuple(rejected))
    scored = sorted(((score(s), s) for s in acceptable), key=lambda x: -x[0])  # stable
    breakdown = tuple((s.name, score_breakdown(reqs, s, graph)) for _v, s in scored) if reasons else ()
    return Validity(tuple(s.name for _v, s in scored), tuple(rejected), tuple(v for v, _s in scored), breakdown)


def is_ranked(reqs: tuple[Requirement, ...]) -> bool:
    """Does ``reqs`` hold a preference (whose scores order the acceptable platforms)?"""
    for r in reqs:
        if type(r) is Preference:
            return True
    return False


class ScalarChecks:
    """The Checks port answered platform by platform (:func:`loop_validity`,
    :func:`platform_failures`), every answer computed afresh.

    It remembers nothing: a run that asks the same questions about the same facts again
    and again (the checker) wraps it in a :class:`~desmon.deployment.memo.MemoChecks` it
    owns, and a run whose facts seldom recur (a fleet, where some platform changed
    between almost any two questions) asks it as it is, sparing the hashing and the old
    states a memo would hold. Memoisation is a property of the instance its caller
    chose, never a global switch.
    """

    #: its answers are :data:`DEFAULT_CHECKS`' own, so a deployer's worker process may
    #: compute them itself (:mod:`desmon.verify.isolation`); a port that must see every
    #: question (the table engine's recording checks) does not say so
    answers_as_default = True

    def compute(self, reqs: tuple[Requirement, ...], states: tuple[PlatformState, ...], graph: Placing, reasons: bool) -> Validity:
        """The answer of :meth:`validity` (implementations refine this)."""
        return loop_validity(reqs, states, graph, reasons)

    def validity(self, reqs: tuple[Requirement, ...], states: tuple[PlatformState, ...], graph: Placing, reasons: bool) -> Validity:
        return self.compute(reqs, states, graph, reasons)

    def platform(self, reqs: tuple[Requirement, ...], state: PlatformState, graph: Placing, first_only: bool) -> tuple[Failure, ...]:
        return platform_failures(reqs, state, graph, first_only)

    def clear(self) -> None:
        """Forget what it remembers (nothing: a memoising subclass refines this)."""

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"


class PlatformMemoChecks(ScalarChecks):
    """:class:`ScalarChecks` whose answers reuse each platform's part: the failures of
    one platform for one question (requirements, graph, ``first_only``) and its
    preference score depend on that platform's facts only, so when one platform's facts
    change (a load, a deployment) the others' parts are looked up, not recomputed. The
    answers are :func:`loop_validity`'s and :func:`platform_failures`', equal object for
    object.

    For a caller that asks about the same few platforms again and again while their
    facts change one at a time, and hands out the same :class:`PlatformState` object
    for the same facts (one robot's SimPy world, whose Query port memoises states):
    the parts are keyed on the identities of the requirement objects and of the state
    (each entry holds them, so an identity cannot be reused while it exists), which
    spares hashing requirements and states. Every memo is cleared past ``size`` entries.
    """

    def __init__(self, *, size: int = _MEMO_SIZE) -> None:
        # ids of a question's requirement objects -> (the requirements, (those ids, their
        # checks (_checks), whether one is a preference))
        self._size = size
        # (each of these is an identity memo, :func:`desmon.deployment.memo.found`)
        self._lookups: dict[tuple[int, ...], tuple[tuple[Requirement, ...], _Question]] = {}
        # id of a requirements tuple -> (the tuple, its _Question): the same lookup for a
        # caller that asks with the same tuple object again (bounded by _TUPLES)
        self._tuples: dict[int, tuple[tuple[Requirement, ...], _Question]] = {}
        # (ids of the requirement objects, id of the state, graph, first_only or None for
        # the score) -> (the state, the requirements, its failures or score): the entry
        # holds the objects whose ids its key names
        self._parts: dict[tuple[Any, ...], tuple[PlatformState, tuple[Requirement, ...], Any]] = {}
        # id of a states tuple -> (the tuple, its platforms in preference order)
        self._orders: dict[int, tuple[tuple[PlatformState, ...], list[PlatformState]]] = {}

    def _question(self, reqs: tuple[Requirement, ...]) -> "_Question":
        """(ids of the objects of ``reqs``, their checks, whether one is a preference, their
        descriptions so far): found by the tuple's identity, else by the ids of its objects
        (each entry holds what its key names); a requirement that is none raises (:func:`_checks`)."""
        tuples = self._tuples
        hit = tuples.get(id(reqs))
        if hit is not None and hit[0] is reqs:
            return hit[1]
        ids = tuple(map(id, reqs))
        found = self._lookups.get(ids)
        question = found[1] if found is not None else kept(self._lookups, self._size, ids, (reqs,), (ids, _checks(reqs), is_ranked(reqs), {}))
        return kept(tuples, _TUPLES, id(reqs), (reqs,), question)  # type: ignore[no-any-return]

    def _part(self, key: tuple[Any, ...], state: PlatformState, reqs: tuple[Requirement, ...], fn: Callable[..., Any], *args: Any) -> Any:
        """The memoised part ``key`` names (``fn(*args)`` on a miss); ``key`` holds the ids of
        ``state`` and ``reqs``, which its entry keeps alive."""
        parts = self._parts
        hit = parts.get(key)
        if hit is not None and hit[0] is state:
            return hit[2]
        return kept(parts, self._size, key, (state, reqs), fn(*args))

    def platform(self, reqs: tuple[Requirement, ...], state: PlatformState, graph: Placing, first_only: bool) -> tuple[Failure, ...]:
        ids, lookups, _ranked_, texts = self._question(reqs)
        key = (ids, id(state), graph, first_only)
        hit = self._parts.get(key)
        if hit is not None and hit[0] is state:
            return hit[2]  # type: ignore[no-any-return]
        return self._part(key, state, reqs, _failures, lookups, state, graph, first_only, texts)  # type: ignore[no-any-return]

    def each_platform(self, reqs: tuple[Requirement, ...], states: Sequence[PlatformState], graph: Placing, first_only: bool) -> list[tuple[Failure, ...]]:
        """:meth:`platform`'s answer for each of ``states``, in their order."""
        ids, lookups, _ranked_, texts = self._question(reqs)
        part = self._part
        return [part((ids, id(st), graph, first_only), st, reqs, _failures, lookups, st, graph, first_only, texts) for st in states]

    def validity(self, reqs: tuple[Requirement, ...], states: tuple[PlatformState, ...], graph: Placing, reasons: bool) -> Validity:
        return self.compute(reqs, states, graph, reasons)

    def _ordered(self, states: tuple[PlatformState, ...]) -> list[PlatformState]:
        """:func:`order_platforms` of ``states``, kept per tuple (the entry holds it)."""
        orders = self._orders
        hit = orders.get(id(states))
        if hit is not None and hit[0] is states:
            return hit[1]
        return kept(orders, _TUPLES, id(states), (states,), order_platforms(states))  # type: ignore[no-any-return]

    def compute(self, reqs: tuple[Requirement, ...], states: tuple[PlatformState, ...], graph: Placing, reasons: bool) -> Validity:
        """:func:`loop_validity`, each platform's failures and score memoised."""
        ids, lookups, ranked, texts = self._question(reqs)  # a requirement that is none raises even without platforms
        first_only = not reasons
        parts = self._parts
        ordered = self._ordered(states)
        failures = []
        for state in ordered:
            key = (ids, id(state), graph, first_only)
            hit = parts.get(key)
            if hit is not None and hit[0] is state:
                failures.append(hit[2])
            else:
                failures.append(self._part(key, state, reqs, _failures, lookups, state, graph, first_only, texts))
        part = self._part

        def score(state: PlatformState) -> float:
            return part((ids, id(state), graph, None), state, reqs, platform_score, reqs, state, graph)  # type: ignore[no-any-return]

        return _assemble(reqs, ordered, failures, graph, reasons, score, ranked)

    def clear(self) -> None:
        self._lookups.clear()
        self._tuples.clear()
        self._parts.clear()
        self._orders.clear()


#: The checks of a caller that names none (a library call, a query port built without
#: one): one platform at a time, remembering nothing (a run memoises on checks it owns,
#: :class:`~desmon.deployment.memo.MemoChecks`). Never reassigned.
DEFAULT_CHECKS = ScalarChecks()


def checks_for(states: Sequence[Any]) -> "ChecksPort":
    """The checks to ask about ``states`` when the caller names none: those a platform
    handle came from (the checker's recording Query port hands out handles, whose facts
    only their checks can read), else :data:`DEFAULT_CHECKS`."""
    if states:
        first = states[0]
        if type(first) is PlatformHandle:
            return first.checks  # type: ignore[no-any-return]
    return DEFAULT_CHECKS


def clear_memos() -> None:
    """Forget what :data:`DEFAULT_CHECKS` remembers (nothing: it memoises no answer)."""
    DEFAULT_CHECKS.clear()


def query_checks(q: "QueryPort") -> "ChecksPort":
    """The Checks port of Query port ``q`` (its ``checks``; None: :data:`DEFAULT_CHECKS`)."""
    checks = q.checks
    return DEFAULT_CHECKS if checks is None else checks


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
    more than :data:`_MEMO_SIZE` entries. A port whose ``validity_memo`` is None (the
    networkx repository, whose states are rebuilt on every call) takes the plain path.
    """
    states = q.platform_states()
    memo: dict[tuple[int, int, bool], tuple[tuple[PlatformState, ...], DeploymentSpec, Validity]] | None = q.validity_memo
    if memo is not None:
        mk = (id(states), id(spec), reasons)
        hit = memo.get(mk)
        if hit is not None and hit[0] is states and hit[1] is spec:
            return hit[2]
    all_states = states
    fixed = q.fixed_platform(spec)
    if fixed is not None:
        states = tuple(s for s in states if s.name == fixed)
    validity = spec_validity(q.constraints(spec), spec.reads, states, all_states, spec.graph, reasons=reasons, checks=query_checks(q))
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
    others = check_validity(tuple(q.constraints(spec)) + spec.reads, states, spec.graph, checks=query_checks(q))
    merged = tuple((name, tuple(others.failures(name)) + tuple(f for f in fails if f not in others.failures(name))) for name, fails in validity.rejected)
    return Validity((), merged)


def deployment_valid(
    spec: DeploymentSpec | None, state: PlatformState, states: Sequence[PlatformState], checks: "ChecksPort | None" = None
) -> tuple[Failure, ...]:
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
        return check_platform(spec.requirements, state, spec.graph, checks=checks)
    if checks is None:
        checks = checks_for((state,))
    fails = check_platform(_joined(spec.requirements, reads, checks), state, spec.graph, checks=checks)
    if fails:
        return fails
    name = state.platform.name
    for r in reads:
        if name not in r.hosts:  # a remote half: read from the other platforms' states
            return input_failures(reads, name, _lookup(states), spec.graph, checks=checks)
    return ()  # input_failures' answer when the platform hosts every kind read
