"""Requirement checking: the paper's ``checkValidity`` with reasons.

The semantics of every requirement kind (docs/design.md §4) lives here and nowhere else.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING, Any, Iterable, Sequence

from desmon.model.requirements import (
    PLATFORM_HAS,
    Attribute,
    DeploymentSpec,
    Capacity,
    Maximum,
    Minimum,
    Option,
    Quantity,
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

__all__ = ["Failure", "Validity", "check_validity", "check_platform", "requirement_holds", "order_platforms", "acceptable_platforms", "validity_for", "deployment_valid", "clear_memos"]


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
    """Result of :func:`check_validity`: acceptable platforms (in preference order) and
    every failure of every rejected platform."""

    acceptable: tuple[str, ...]
    rejected: tuple[tuple[str, tuple[Failure, ...]], ...]

    def failures(self, platform: str) -> tuple[Failure, ...]:
        for name, fails in self.rejected:
            if name == platform:
                return fails
        return ()

    def explain(self) -> str:
        lines = [f"acceptable: {', '.join(self.acceptable) or '(none)'}"]
        for _name, fails in self.rejected:
            lines.extend(str(f) for f in fails)
        return "\n".join(lines)


def _option_holds(option: Option, state: PlatformState) -> bool:
    if option.attribute is not None:
        return str(state.platform.attribute(option.attribute)) == str(option.value)
    return any(d.matches(option.device_kind or "", option.vendor) for d in state.devices)


def _fmt(x: float) -> str:
    return f"{x:g}"


def requirement_holds(req: Requirement, state: PlatformState, graph: Placing) -> str | None:
    """``None`` if ``req`` holds on ``state`` for ``graph``, else the reason it fails."""
    if isinstance(req, Quantity):
        have = sum(1 for d in state.devices if d.kind == req.device_kind)
        if have >= req.count:
            return None
        return f"{have} working {req.device_kind} device(s), needs {req.count}"
    if isinstance(req, Capacity):
        cap = state.platform.capacity(req.resource)
        if cap is None:
            return f"has no {req.resource} capacity"
        if graph is None or type(graph) is str:
            others = state.used_by(req.resource, excluding=graph)
        else:  # a tuple: the graph and the graphs an upgrade would free (see check_validity)
            others = [(g, a) for g, a in state.used_by(req.resource) if g not in graph]
        load = state.load_of(req.resource)
        free = cap - sum(a for _g, a in others) - load
        if free >= req.amount:
            return None
        unit = " MB" if req.resource == "memory" else ""
        parts = [f"capacity {_fmt(cap)}"]
        parts += [f"used by {g} {_fmt(a)}" for g, a in others]
        parts.append(f"load {_fmt(load)}")
        return f"{_fmt(free)}{unit} free ({', '.join(parts)})"
    if isinstance(req, Minimum):
        value = state.platform.prop(req.prop)
        if value is None:
            return f"has no property {req.prop!r}"
        return None if value >= req.value else f"{req.prop} is {_fmt(value)}"
    if isinstance(req, Maximum):
        value = state.platform.prop(req.prop)
        if value is None:
            return f"has no property {req.prop!r}"
        return None if value <= req.value else f"{req.prop} is {_fmt(value)}"
    if isinstance(req, Attribute):
        if req.name == PLATFORM_HAS:
            if any(d.kind == req.value for d in state.devices):
                return None
            return f"no working {req.value} attached"
        actual = state.platform.attribute(req.name)
        if actual is not None and str(actual) == str(req.value):
            return None
        return f"{req.name} is {actual!r}" if actual is not None else f"has no attribute {req.name!r}"
    if isinstance(req, Selection):
        have = [o.describe() for o in req.options if _option_holds(o, state)]
        if len(have) >= req.at_least:
            return None
        return f"{len(have)} of the options available ({', '.join(have) or 'none'}), needs {req.at_least}"
    raise TypeError(f"not a requirement: {req!r}")  # pragma: no cover - exhaustive over Requirement


_DOWN = "platform is down"


def check_platform(
    requirements: Iterable[Requirement], state: PlatformState, graph: Placing, *, first_only: bool = False
) -> tuple[Failure, ...]:
    """Every requirement ``state`` fails for ``graph`` (only the first if ``first_only``);
    a down platform fails them all. Memoised: it is pure and the deployer, the invariants
    and the checker ask it again and again about the same facts."""
    reqs = requirements if type(requirements) is tuple else tuple(requirements)
    if _observer is not None:
        return _observer.platform(reqs, state, graph, first_only)  # type: ignore[no-any-return]
    return _check_platform(reqs, state, graph, first_only)  # type: ignore[arg-type]


@lru_cache(maxsize=_MEMO_SIZE)
def _check_platform(
    requirements: tuple[Requirement, ...], state: PlatformState, graph: Placing, first_only: bool
) -> tuple[Failure, ...]:
    if not state.up:
        return (Failure(state.name, "platform up", _DOWN),)
    out = []
    for req in requirements:
        reason = requirement_holds(req, state, graph)
        if reason is not None:
            out.append(Failure(state.name, req.describe(), reason))
            if first_only:
                break
    return tuple(out)


def clear_memos() -> None:
    """Forget every memoised validity result (tests; memory)."""
    _check_platform.cache_clear()
    _check_validity.cache_clear()


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
    ``reasons`` is False, the fast path of the deployer). Results are memoised (pure).
    """
    reqs = requirements if type(requirements) is tuple else tuple(requirements)
    if _observer is not None:
        return _observer.validity(reqs, states if type(states) is tuple else tuple(states), graph, reasons)  # type: ignore[no-any-return]
    return _check_validity(reqs, states if type(states) is tuple else tuple(states), graph, reasons)  # type: ignore[arg-type]


@lru_cache(maxsize=_MEMO_SIZE)
def _check_validity(
    reqs: tuple[Requirement, ...], states: tuple[PlatformState, ...], graph: Placing, reasons: bool
) -> Validity:
    acceptable: list[str] = []
    rejected: list[tuple[str, tuple[Failure, ...]]] = []
    check = _check_platform.__wrapped__  # memoised as a whole here; per pair only in check_platform
    for state in order_platforms(states):
        fails = check(reqs, state, graph, not reasons)
        if fails:
            rejected.append((state.name, fails))
        else:
            acceptable.append(state.name)
    return Validity(tuple(acceptable), tuple(rejected))


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
    validity = check_validity(q.constraints(spec), states, spec.graph, reasons=reasons)
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
    return validity_for(q, spec)


def deployment_valid(spec: DeploymentSpec | None, state: PlatformState) -> tuple[Failure, ...]:
    """Why an active deployment of ``spec`` on ``state`` is invalid (empty if it is valid).

    Used by the corrected deployer's bookkeeping and by the invariants alike: up, on its
    EXECUTABLE_ON platform if fixed, every requirement met (own Capacity share excluded).
    """
    if spec is None:
        return (Failure(state.name, "deployment information", "missing"),)
    if spec.fixed_platform is not None and spec.fixed_platform != state.name:
        return (Failure(state.name, f"EXECUTABLE_ON {spec.fixed_platform}", "runs on another platform"),)
    return check_platform(spec.requirements, state, spec.graph)
