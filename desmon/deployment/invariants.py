"""The named invariants of docs/design.md §9, defined once.

The checker, the fuzzer and the simulation audit all evaluate these same functions on
a :class:`SystemView`, built from whatever holds the state (the networkx repository
or the checker's compact state) by :func:`view_of`.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any, Callable, Container

from desmon.deployment.deployer import fits_if_freed, upgrade_due
from desmon.deployment.ports import (
    DEPLOYMENT_FAILED, DEPLOYMENT_INFORMATION_MISSING, NO_ACCEPTABLE_PLATFORMS, STOPPING_FAILED, QueryPort, RaiseError, Start, Stop,
)
from desmon.deployment.validity import Failure, deployment_valid, validity_for
from desmon.errors import ModelError
from desmon.model.requirements import DeploymentSpec, fits
from desmon.model.system import PlatformState

__all__ = [
    "SystemView", "Invariant", "INVARIANTS", "view_of", "make_view", "check_invariants", "get_invariants", "validly_active", "validly_active_among",
    "ReactionBook", "raise_problem", "judge_reaction", "TRANSITION_INVARIANTS", "INSTANT_INVARIANTS", "start_findings",
]


@dataclass(frozen=True, slots=True)
class SystemView:
    """Everything an invariant reads, after a reaction (a "stable" state).

    ``running`` is the infrastructure's own list of instances and ``stops`` / ``history``
    the number of stops it performed and of DEPLOYMENT_HISTORY edges; engines that
    cannot observe one of them leave it ``None`` and the part of ``history`` that needs
    it is skipped.
    """

    states: tuple[PlatformState, ...]
    specs: tuple[DeploymentSpec, ...]
    standing: frozenset[str]
    slots: tuple[tuple[str, ...], ...]
    running: tuple[tuple[str, str], ...] | None = None
    stops: int | None = None
    history: int | None = None
    #: the deployer's reaction ``react(q, slots, changed, context_changed)``, for the
    #: ``no-flapping`` property (which re-runs it on this view); None skips that property
    react: Callable[..., Any] | None = None
    #: the Checks port requirement questions about ``states`` go to (None: the default)
    checks: Any = None
    # :attr:`deployments`, computed on first use (a performance cache: several
    # invariants read it; no part of equality, repr or the constructor)
    _deployments: tuple[tuple[str, str], ...] | None = field(default=None, init=False, repr=False, compare=False)
    # :meth:`failures` of each (graph, platform) asked, and :func:`validly_active`, computed
    # on first use (a performance cache: the view is immutable and several invariants ask)
    _failures: dict[tuple[str, str], tuple[Failure, ...]] | None = field(default=None, init=False, repr=False, compare=False)
    _valid: frozenset[str] | None = field(default=None, init=False, repr=False, compare=False)

    @property
    def deployments(self) -> tuple[tuple[str, str], ...]:
        """Every active (graph, platform) pair, sorted (derived from ``states``)."""
        d = self._deployments
        if d is None:
            d = tuple(sorted((g, s.name) for s in self.states for g, _use in s.deployed))
            object.__setattr__(self, "_deployments", d)
        return d

    def failures(self, graph: str, state: PlatformState) -> tuple[Failure, ...]:
        """Why the active deployment of ``graph`` on ``state`` (one of :attr:`states`) is
        invalid (:func:`~desmon.deployment.validity.deployment_valid`; empty if valid),
        asked once per view."""
        memo = self._failures
        if memo is None:
            memo = {}
            object.__setattr__(self, "_failures", memo)
        key = (graph, state.platform.name)
        fails = memo.get(key)
        if fails is None:
            fails = memo[key] = deployment_valid(self.spec(graph), state, self.states, self.checks)
        return fails

    def spec(self, graph: str) -> DeploymentSpec | None:
        for s in self.specs:
            if s.graph == graph:
                return s
        return None

    def state(self, platform: str) -> PlatformState:
        for s in self.states:
            if s.name == platform:
                return s
        raise KeyError(platform)


#: the slots of :class:`SystemView`, in field order, as their setters (see :func:`make_view`)
_VIEW_SETTERS = tuple(
    getattr(SystemView, name).__set__
    for name in ("states", "specs", "standing", "slots", "running", "stops", "history", "react", "checks", "_deployments", "_failures", "_valid")
)


def make_view(
    states: tuple[PlatformState, ...],
    specs: tuple[DeploymentSpec, ...],
    standing: frozenset[str],
    slots: tuple[tuple[str, ...], ...],
    running: tuple[tuple[str, str], ...] | None = None,
    stops: int | None = None,
    history: int | None = None,
    react: Callable[..., Any] | None = None,
    checks: Any = None,
) -> SystemView:
    """``SystemView(states, specs, ...)``, built without the frozen class's ``__init__``
    (which sets each slot through ``object.__setattr__``): every audit builds one. Equal
    to the constructor's view (the class has no ``__post_init__``)."""
    view = object.__new__(SystemView)
    values = (states, specs, standing, slots, running, stops, history, react, checks, None, None, None)
    for set_slot, value in zip(_VIEW_SETTERS, values):
        set_slot(view, value)
    return view


def view_of(
    q: QueryPort,
    specs: tuple[DeploymentSpec, ...],
    standing: frozenset[str],
    slots: tuple[tuple[str, ...], ...],
    *,
    running: tuple[tuple[str, str], ...] | None = None,
    stops: int | None = None,
    history: int | None = None,
    react: Callable[..., Any] | None = None,
) -> SystemView:
    return make_view(q.platform_states(), specs, standing, slots, running, stops, history, react, q.checks)


def validly_active(view: SystemView) -> frozenset[str]:
    """Graphs active on at least one platform where their deployment is valid (computed
    once per view: :meth:`SystemView.failures` of each deployment, in the states' order)."""
    valid = view._valid
    if valid is None:
        failures = view.failures
        valid = frozenset(g for s in view.states for g, _use in s.deployed if not failures(g, s))
        object.__setattr__(view, "_valid", valid)
    return valid


def validly_active_among(
    states: tuple[PlatformState, ...],
    spec: Callable[[str], DeploymentSpec | None],
    graphs: Container[str] | None = None,
    checks: Any = None,
) -> frozenset[str]:
    """:func:`validly_active` on ``states`` (``spec`` maps a graph to its specification),
    restricted to ``graphs`` when given: only their deployments are tested, which is all
    :meth:`~desmon.deployment.core.DeploymentCore.settle` needs (no view is built)."""
    return frozenset(
        g
        for s in states
        for g, _use in s.deployed
        if (graphs is None or g in graphs) and not deployment_valid(spec(g), s, states, checks)
    )


Check = Callable[[SystemView], str | None]


@dataclass(frozen=True, slots=True)
class Invariant:
    """A named ``always`` property: ``check(view)`` returns None or what is wrong.

    ``at_start(view, graph, platform)``: what the start of ``graph`` on ``platform`` broke of
    it, ``view`` being the state right after the start (:func:`start_findings`); None: the
    property is judged on the whole view there."""

    name: str
    description: str
    check: Check
    at_start: Callable[[SystemView, str, str], str | None] | None = None


def _valid_or_error(v: SystemView) -> str | None:
    for g, p in v.deployments:
        fails = v.failures(g, v.state(p))
        if fails and g not in v.standing:
            return f"{g} is active on {p}, which is invalid ({'; '.join(f.requirement + ': ' + f.reason for f in fails)}), and no error stands for it"
    return None


def _no_overcommit(v: SystemView) -> str | None:
    for s in v.states:
        deployed = s.deployed
        capacities = s.platform.capacities
        if not deployed and all(cap >= 0 for _res, cap in capacities):
            continue  # nothing consumes: a total of 0 exceeds no capacity of 0 or more
        for res, cap in capacities:
            used = s.used_by(res) if deployed else []
            total = sum(a for _g, a in used)
            if not fits(total, cap):
                who = ", ".join(f"{g} {a:g}" for g, a in used)
                return f"{s.name}: deployments consume {total:g} {res} ({who}) but the capacity is {cap:g}"
    return None


def _overcommit_by_start(v: SystemView, graph: str, platform: str) -> str | None:
    """``no-overcommit`` as the start of ``graph`` on ``platform`` broke it: a capacity of that
    platform the deployments exceed after the start, of a resource the started graph
    consumes (it put more on it). A capacity exceeded only by what ran before (a
    requirement change raised a running graph's Capacity) is not the start's, nor one of
    another platform."""
    for s in v.states:
        if s.name != platform:
            continue
        for res, cap in s.platform.capacities:
            used = s.used_by(res)
            total = sum(a for _g, a in used)
            if not fits(total, cap) and any(g == graph for g, _a in used):
                who = ", ".join(f"{g} {a:g}" for g, a in used)
                return f"{s.name}: deployments consume {total:g} {res} ({who}) but the capacity is {cap:g}"
    return None


def _of_started_graph(check: Check) -> Callable[[SystemView, str, str], str | None]:
    """``check`` on the started graph's own instances (``single-instance``, ``fixed``): the
    same facts, with that graph's deployments as the view's (a derived field, set here)."""
    def at_start(v: SystemView, graph: str, platform: str) -> str | None:
        own = replace(v)
        object.__setattr__(own, "_deployments", tuple(d for d in v.deployments if d[0] == graph))
        return check(own)

    return at_start


def _single_instance(v: SystemView) -> str | None:
    deployments = v.deployments
    if len({g for g, _p in deployments}) == len(deployments):
        return None  # no graph twice
    where: dict[str, list[str]] = {}
    for g, p in deployments:
        where.setdefault(g, []).append(p)
    for g, ps in sorted(where.items()):
        if len(ps) > 1:
            return f"{g} is active on {len(ps)} platforms: {', '.join(ps)}"
    return None


def _coverage(v: SystemView) -> str | None:
    valid = validly_active(v)
    for slot in v.slots:
        if any(g in valid for g in slot):
            continue
        if all(g in v.standing for g in slot):
            continue
        missing = [g for g in slot if g not in v.standing]
        return f"the selector wants {' or '.join(slot)} but none is active on a valid platform and no error explains {', '.join(missing)}"
    return None


def _errors_current(v: SystemView) -> str | None:
    if not v.standing:
        return None
    valid = validly_active(v)
    active = {g for g, _p in v.deployments}
    for g in sorted(v.standing):
        slots = [slot for slot in v.slots if g in slot]
        if not slots:
            return f"an error stands for {g}, which the selector does not want in this context"
        if g in valid:
            where = ", ".join(p for h, p in v.deployments if h == g)
            return f"an error stands for {g}, which runs validly on {where}"
        if g not in active and all(any(h in valid for h in slot) for slot in slots):
            served = ", ".join(next(h for h in slot if h in valid) for slot in slots)
            return f"an error stands for {g}, but its slot is served by {served} and {g} is not active: the error is stale"
    return None


def _history(v: SystemView) -> str | None:
    if v.running is not None and tuple(sorted(v.running)) != v.deployments:
        extra = sorted(set(v.deployments) - set(v.running))
        lost = sorted(set(v.running) - set(v.deployments))
        return f"DEPLOYED_ON edges and running detectors disagree: edges without detector {extra}, detectors without edge {lost}"
    if v.stops is not None and v.history is not None and v.stops != v.history:
        return f"{v.stops} deployments were stopped but {v.history} DEPLOYMENT_HISTORY edges exist"
    return None


def _fixed(v: SystemView) -> str | None:
    if not _any_fixed(v.specs):
        return None  # no specification names a fixed platform
    for g, p in v.deployments:
        spec = v.spec(g)
        if spec is not None and spec.fixed_platform is not None and spec.fixed_platform != p:
            return f"{g} is fixed to {spec.fixed_platform} (EXECUTABLE_ON) but runs on {p}"
    return None


def _any_fixed(specs: tuple[DeploymentSpec, ...]) -> bool:
    """Does a specification of ``specs`` name a fixed platform?"""
    return any(s is not None and s.fixed_platform is not None for s in specs)


class _ViewQuery:
    """The Query port over a :class:`SystemView` (read-only), for re-running a reaction."""

    validity_memo = None
    specs_version = None

    def __init__(self, view: SystemView) -> None:
        self.view = view
        self.checks = view.checks

    def deployment_information(self, graph: str) -> DeploymentSpec | None:
        return self.view.spec(graph)

    def fixed_platform(self, spec: DeploymentSpec) -> str | None:
        return spec.fixed_platform

    def constraints(self, spec: DeploymentSpec) -> tuple:
        return spec.requirements

    def platform_states(self) -> tuple[PlatformState, ...]:
        return self.view.states

    def deployed_on(self, graph: str) -> tuple[str, ...]:
        return tuple(p for g, p in self.view.deployments if g == graph)

    def active_deployments(self, platform: str) -> tuple[str, ...]:
        return tuple(sorted(g for g, _use in self.view.state(platform).deployed))

    def deployments(self) -> tuple[tuple[str, str], ...]:
        return self.view.deployments

    def perception_graph(self, deployment: str) -> str:
        return deployment

    def context(self) -> str | None:
        return None


def _transition_only(v: SystemView) -> str | None:
    return None  # judged on a reaction (judge_reaction), not on a state alone


def _no_flapping(v: SystemView) -> str | None:
    """Re-run the reaction with nothing changed, executing nothing (every Start answered
    as failed, every Stop as done): it must stop no valid deployment of a graph that
    rebalances. If it would, the deployment moves again although the environment is
    unchanged -- it flaps (or keeps retrying a move that failed)."""
    if v.react is None or not any(s.rebalance is not None for s in v.specs):
        return None
    wanted = {g for slot in v.slots for g in slot}
    reaction = v.react(_ViewQuery(v), v.slots, (), False)
    outcome: bool | None = None
    for _ in range(10_000):  # a reaction is finite; the bound only guards a runaway user deployer
        try:
            cmd = reaction.send(outcome)
        except StopIteration:
            return None
        outcome = False if isinstance(cmd, Start) else True if isinstance(cmd, Stop) else None
        if not isinstance(cmd, Stop) or cmd.graph not in wanted or (cmd.graph, cmd.platform) not in v.deployments:
            continue
        spec = v.spec(cmd.graph)
        if spec is not None and spec.rebalance is not None and not v.failures(cmd.graph, v.state(cmd.platform)):
            return (
                f"with nothing changed the deployer would move {cmd.graph} off {cmd.platform} again, where it runs validly "
                f"(rebalance min_gain {spec.rebalance:g}): it flaps"
            )
    return None


# ------------------------------------------------------------------------------------
# transition properties: judged on one reaction (what it did) and the state it left
# ------------------------------------------------------------------------------------
@dataclass(slots=True)
class ReactionBook:
    """What one reaction did, as ``errors-justified`` and ``preferred-when-possible``
    judge it: the stimulus it answered, each graph's tried platforms, its last start or
    stop (verb, platform, succeeded), the kind of the last error raised for it, and the
    first error raised without its reason holding at that instant."""

    changed: tuple[str, ...]
    context_changed: bool
    tried: dict[str, set[str]] = field(default_factory=dict)
    last: dict[str, tuple[str, str, bool]] = field(default_factory=dict)
    raised: dict[str, str] = field(default_factory=dict)
    bad_raise: str | None = None

    def note(self, cmd: object, outcome: bool | None) -> None:
        """Record an executed Start or Stop and its outcome."""
        if type(cmd) is Start:
            self.tried.setdefault(cmd.graph, set()).add(cmd.platform)
            self.last[cmd.graph] = ("start", cmd.platform, bool(outcome))
        elif type(cmd) is Stop:
            self.last[cmd.graph] = ("stop", cmd.platform, bool(outcome))


def raise_problem(cmd: RaiseError, book: ReactionBook, q: QueryPort) -> str | None:
    """Why the error ``cmd`` is not true at the instant it is raised (None if it is):

    * ``no_acceptable_platforms`` -- no platform is acceptable for the graph now;
    * ``deployment_failed`` -- the graph's last start or stop in this reaction was a start
      (on the error's platform, when it names one) that failed or was refused;
    * ``stopping_failed`` -- likewise a stop that failed;
    * ``deployment_information_missing`` -- the graph has no deployment specification.
    """
    g, kind = cmd.graph, cmd.kind
    if kind in (DEPLOYMENT_FAILED, STOPPING_FAILED):
        verb = "start" if kind == DEPLOYMENT_FAILED else "stop"
        last = book.last.get(g)
        if last is None or last[0] != verb:
            return f"{cmd.kind} raised for {g}, but no {verb} of {g} preceded it in this reaction"
        if last[2]:
            return f"{cmd.kind} raised for {g}, but its last {verb} (on {last[1]}) succeeded"
        if cmd.platform is not None and cmd.platform != last[1]:
            return f"{cmd.kind} raised for {g} on {cmd.platform}, but its last {verb} was on {last[1]}"
        return None
    spec = q.deployment_information(g)
    if kind == DEPLOYMENT_INFORMATION_MISSING:
        return None if spec is None else f"{kind} raised for {g}, which has a deployment specification"
    if kind == NO_ACCEPTABLE_PLATFORMS:
        if spec is None:
            return f"{kind} raised for {g}, which has no deployment specification (that is {DEPLOYMENT_INFORMATION_MISSING})"
        acceptable = validity_for(q, spec, reasons=False).acceptable
        if acceptable:
            return f"{kind} raised for {g} while {', '.join(acceptable)} {'is' if len(acceptable) == 1 else 'are'} acceptable"
    return None


def judge_reaction(
    q: QueryPort,
    book: ReactionBook,
    standing: frozenset[str],
    slots: tuple[tuple[str, ...], ...],
    spec_of: Callable[[str], DeploymentSpec | None],
) -> list[tuple[str, str]]:
    """The transition halves of ``errors-justified`` and ``preferred-when-possible`` for
    one reaction (``book``) and the state it left (through ``q``); (invariant, message)
    for each broken one (docs/design.md §7-§9)."""
    out: list[tuple[str, str]] = []
    if book.bad_raise is not None:
        out.append(("errors-justified", book.bad_raise))
    for g in sorted(standing):
        # a standing error is true only while no acceptable platform is left untried:
        # a graph still running (its stop failed) is judged by valid-or-error instead
        spec = spec_of(g)
        if spec is None or q.deployed_on(g):
            continue
        untried = [p for p in validity_for(q, spec, reasons=False).acceptable if p not in book.tried.get(g, ())]
        if untried:
            why = f"{book.raised[g]} raised in this reaction" if g in book.raised else "standing from before"
            out.append((
                "errors-justified",
                f"an error stands for {g} ({why}) although it is acceptable on {', '.join(untried)}, which this reaction did not try",
            ))
            break
    for slot in slots:
        g = slot[0]
        spec = spec_of(g)
        if spec is None or g in book.tried or q.deployed_on(g):
            continue
        running = [f for f in slot[1:] if q.deployed_on(f)]
        fits = fits_if_freed(g, spec, q, running)
        if upgrade_due(spec, fits, book.changed, book.context_changed):
            cause = "the context changed" if book.context_changed else f"{', '.join(book.changed)} changed"
            freed = f" with {', '.join(running)} stopped" if running else ""
            serves = f"{', '.join(running)} serves the slot" if running else "the slot is unserved"
            out.append((
                "preferred-when-possible",
                f"{g} would be acceptable on {', '.join(fits)}{freed} and {cause}, but the reaction did not try it: {serves}",
            ))
            break
    return out


INVARIANTS: dict[str, Invariant] = {
    inv.name: inv
    for inv in (
        Invariant("valid-or-error", "every active deployment runs on an up platform meeting all its requirements, or an error stands for its graph", _valid_or_error),
        Invariant(
            "no-overcommit", "on every platform the Capacity consumed by active deployments stays within the capacity", _no_overcommit,
            _overcommit_by_start,
        ),
        Invariant("single-instance", "no perception graph is active on two platforms", _single_instance, _of_started_graph(_single_instance)),
        Invariant(
            "coverage",
            "after each reaction every graph the selector wants is active on a valid platform, or an error explains why not "
            "(it checks the rules' slots: a risky action no rule covers has none, so it holds there, and the exposure counts "
            "that time as unmonitored, cause no_rule, with a warning)",
            _coverage,
        ),
        Invariant("errors-current", "a standing error describes the present: its graph is wanted, not validly active, and either active on an invalid platform or in a slot no alternative serves", _errors_current),
        Invariant("history", "every stop leaves one DEPLOYMENT_HISTORY edge; every DEPLOYED_ON edge matches a running detector", _history),
        Invariant("fixed", "a fixed deployment runs only on its EXECUTABLE_ON platform", _fixed, _of_started_graph(_fixed)),
        Invariant(
            "errors-justified",
            "every error is true when raised (no_acceptable_platforms: no platform is acceptable; deployment_failed / stopping_failed: the graph's last start / stop just failed; deployment_information_missing: no specification), and an error stands after a reaction only while every platform acceptable for its graph was tried in that reaction",
            _transition_only,
        ),
        Invariant(
            "preferred-when-possible",
            "after a reaction to a change that may let a slot's preferred alternative run (the context, a platform where it would fit with the slot's fallbacks stopped, or one it reads), the preferred alternative runs or the reaction tried it",
            _transition_only,
        ),
        Invariant(
            "no-flapping",
            "with the environment unchanged no deployment moves again: re-running the reaction with nothing changed moves no valid deployment of a graph that rebalances",
            _no_flapping,
        ),
    )
}


#: Invariants that are physical facts at every instant, not only when quiescent: every
#: engine also evaluates them after each start that succeeds inside a reaction, on what
#: the start changed (:func:`start_findings`: the checker through ``Bounds.instantaneous``,
#: the simulation's audit, the fuzzer and every replay). A stop breaks none of them (it
#: leaves fewer instances and less consumed), so none is judged after a stop.
INSTANT_INVARIANTS = ("single-instance", "no-overcommit", "fixed")


#: The invariants judged on a reaction, not on a state alone (their ``check`` of a view
#: says nothing; :func:`judge_reaction` and the core's move audit report them).
TRANSITION_INVARIANTS = ("errors-justified", "preferred-when-possible")


def get_invariants(names: list[str] | tuple[str, ...] | None = None) -> tuple[Invariant, ...]:
    """The invariants called ``names`` (all if None; none if empty), each named once; a
    ModelError lists the valid names."""
    if names is None:
        return tuple(INVARIANTS.values())
    out = []
    for n in names:
        if n not in INVARIANTS:
            raise ModelError(f"unknown invariant {n!r}: choose from {', '.join(INVARIANTS)}")
        if INVARIANTS[n] in out:
            raise ModelError(f"invariant {n!r} is named twice: name each invariant once")
        out.append(INVARIANTS[n])
    return tuple(out)


def start_findings(view: SystemView, invariants: tuple[Invariant, ...], graph: str, platform: str) -> list[tuple[str, str]]:
    """(name, message) of each of ``invariants`` the start of ``graph`` on ``platform``
    broke, ``view`` being the state right after it: each judged on what a start changes
    (its :attr:`Invariant.at_start`): the started graph's own instances (``single-instance``,
    ``fixed``), the capacities of the platform it started on that are exceeded after it in
    a resource it consumes (``no-overcommit``). A violation it did not add to (the
    environment's, such as a requirement change that raised a running graph's
    consumption, or another platform's) is not charged to it; the state a reaction ends
    in is judged whole. Every engine audits a reaction's starts with this function."""
    out: list[tuple[str, str]] = []
    for inv in invariants:
        msg = inv.at_start(view, graph, platform) if inv.at_start is not None else inv.check(view)
        if msg is not None:
            out.append((inv.name, msg))
    return out


def check_invariants(view: SystemView, invariants: tuple[Invariant, ...] | None = None) -> list[tuple[str, str]]:
    """(name, message) of every invariant violated by ``view``."""
    out = []
    for inv in invariants or tuple(INVARIANTS.values()):
        msg = inv.check(view)
        if msg is not None:
            out.append((inv.name, msg))
    return out
