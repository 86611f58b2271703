"""The named invariants of docs/design.md §9, defined once.

The checker, the fuzzer and the simulation audit all evaluate these same functions on
a :class:`SystemView`, built from whatever holds the state (the networkx repository
or the checker's compact state) by :func:`view_of`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Container

from desmon.deployment.ports import QueryPort, Start, Stop
from desmon.deployment.validity import deployment_valid
from desmon.errors import ModelError
from desmon.model.requirements import DeploymentSpec
from desmon.model.system import PlatformState

__all__ = ["SystemView", "Invariant", "INVARIANTS", "view_of", "check_invariants", "get_invariants", "validly_active", "validly_active_among"]


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
    # :attr:`deployments`, computed on first use (a performance cache: several
    # invariants read it; no part of equality, repr or the constructor)
    _deployments: tuple[tuple[str, str], ...] | None = field(default=None, init=False, repr=False, compare=False)

    @property
    def deployments(self) -> tuple[tuple[str, str], ...]:
        """Every active (graph, platform) pair, sorted (derived from ``states``)."""
        d = self._deployments
        if d is None:
            d = tuple(sorted((g, s.name) for s in self.states for g, _use in s.deployed))
            object.__setattr__(self, "_deployments", d)
        return d

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
    return SystemView(q.platform_states(), specs, standing, slots, running, stops, history, react)


def validly_active(view: SystemView) -> frozenset[str]:
    """Graphs active on at least one platform where their deployment is valid."""
    return validly_active_among(view.states, view.spec)


def validly_active_among(
    states: tuple[PlatformState, ...],
    spec: Callable[[str], DeploymentSpec | None],
    graphs: Container[str] | None = None,
) -> frozenset[str]:
    """:func:`validly_active` on ``states`` (``spec`` maps a graph to its specification),
    restricted to ``graphs`` when given: only their deployments are tested, which is all
    :meth:`~desmon.deployment.core.DeploymentCore.settle` needs (no view is built)."""
    return frozenset(
        g
        for s in states
        for g, _use in s.deployed
        if (graphs is None or g in graphs) and not deployment_valid(spec(g), s, states)
    )


Check = Callable[[SystemView], str | None]


@dataclass(frozen=True, slots=True)
class Invariant:
    """A named ``always`` property: ``check(view)`` returns None or what is wrong."""

    name: str
    description: str
    check: Check


def _valid_or_error(v: SystemView) -> str | None:
    for g, p in v.deployments:
        fails = deployment_valid(v.spec(g), v.state(p), v.states)
        if fails and g not in v.standing:
            return f"{g} is active on {p}, which is invalid ({'; '.join(f.requirement + ': ' + f.reason for f in fails)}), and no error stands for it"
    return None


def _no_overcommit(v: SystemView) -> str | None:
    for s in v.states:
        for res, cap in s.platform.capacities:
            used = s.used_by(res)
            total = sum(a for _g, a in used)
            if total > cap:
                who = ", ".join(f"{g} {a:g}" for g, a in used)
                return f"{s.name}: deployments consume {total:g} {res} ({who}) but the capacity is {cap:g}"
    return None


def _single_instance(v: SystemView) -> str | None:
    where: dict[str, list[str]] = {}
    for g, p in v.deployments:
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
    for g, p in v.deployments:
        spec = v.spec(g)
        if spec is not None and spec.fixed_platform is not None and spec.fixed_platform != p:
            return f"{g} is fixed to {spec.fixed_platform} (EXECUTABLE_ON) but runs on {p}"
    return None


class _ViewQuery:
    """The Query port over a :class:`SystemView` (read-only), for re-running a reaction."""

    def __init__(self, view: SystemView) -> None:
        self.view = view

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
        if spec is not None and spec.rebalance is not None and not deployment_valid(spec, v.state(cmd.platform), v.states):
            return (
                f"with nothing changed the deployer would move {cmd.graph} off {cmd.platform} again, where it runs validly "
                f"(rebalance min_gain {spec.rebalance:g}): it flaps"
            )
    return None


INVARIANTS: dict[str, Invariant] = {
    inv.name: inv
    for inv in (
        Invariant("valid-or-error", "every active deployment runs on an up platform meeting all its requirements, or an error stands for its graph", _valid_or_error),
        Invariant("no-overcommit", "on every platform the Capacity consumed by active deployments stays within the capacity", _no_overcommit),
        Invariant("single-instance", "no perception graph is active on two platforms", _single_instance),
        Invariant("coverage", "after each reaction every graph the selector wants is active on a valid platform, or an error explains why not", _coverage),
        Invariant("errors-current", "a standing error describes the present: its graph is wanted, not validly active, and either active on an invalid platform or in a slot no alternative serves", _errors_current),
        Invariant("history", "every stop leaves one DEPLOYMENT_HISTORY edge; every DEPLOYED_ON edge matches a running detector", _history),
        Invariant("fixed", "a fixed deployment runs only on its EXECUTABLE_ON platform", _fixed),
        Invariant(
            "no-flapping",
            "with the environment unchanged no deployment moves again: re-running the reaction with nothing changed moves no valid deployment of a graph that rebalances",
            _no_flapping,
        ),
    )
}


def get_invariants(names: list[str] | tuple[str, ...] | None = None) -> tuple[Invariant, ...]:
    """The invariants called ``names`` (all if None); a ModelError lists the valid names."""
    if not names:
        return tuple(INVARIANTS.values())
    out = []
    for n in names:
        if n not in INVARIANTS:
            raise ModelError(f"unknown invariant {n!r}: choose from {', '.join(INVARIANTS)}")
        out.append(INVARIANTS[n])
    return tuple(out)


def check_invariants(view: SystemView, invariants: tuple[Invariant, ...] | None = None) -> list[tuple[str, str]]:
    """(name, message) of every invariant violated by ``view``."""
    out = []
    for inv in invariants or tuple(INVARIANTS.values()):
        msg = inv.check(view)
        if msg is not None:
            out.append((inv.name, msg))
    return out
