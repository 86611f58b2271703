"""The deployer: Algorithm 1 (``deploy``) and Algorithm 2 (``check_deployment``).

Two variants, selected by name through :data:`DEPLOYERS`:

``paper``
    The paper's Algorithms 1 and 2, transcribed line by line, early ``return``\\ s
    included (line numbers in the comments refer to the paper).
``desmon`` (default)
    The corrected algorithm of docs/design.md §5: every requested graph is handled,
    Capacity is accounted across concurrent deployments (each start is visible to the
    next check), a migration stops the old instance before starting the new one, every
    deployment on a changed platform is re-checked, a still-valid deployment is kept,
    and no invalid deployment is left without an error.

Both are generators over :mod:`desmon.deployment.ports` commands and only read through
the :class:`~desmon.deployment.ports.QueryPort`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Generator, Iterable

from desmon.deployment.memo import MemoChecks
from desmon.deployment.ports import (
    DEPLOYMENT_FAILED,
    DEPLOYMENT_INFORMATION_MISSING,
    NO_ACCEPTABLE_PLATFORMS,
    STOPPING_FAILED,
    Command,
    QueryPort,
    RaiseError,
    Reaction,
    Start,
    Stop,
    relay,
)
from desmon.deployment.validity import check_validity, spec_validity, validity_for
from desmon.errors import ModelError
from desmon.model.checks import check_flag, check_text
from desmon.model.requirements import DeploymentSpec

__all__ = [
    "Deployer", "PAPER", "DESMON", "DESMON_KEEP_FALLBACK", "DEPLOYERS", "get_deployer", "ensure_deployed",
    "make_desmon_react", "upgrade_due", "fits_if_freed", "BREAK_BEFORE_MAKE", "KEEP_FALLBACK", "UPGRADE_POLICIES",
]

#: Generator returning True when the graph ended up deployed.
Placement = Generator[Command, "bool | None", bool]


# ----------------------------------------------------------------------------------
# paper: literal transcription
# ----------------------------------------------------------------------------------
def paper_deploy(graphs: Iterable[str], q: QueryPort) -> Reaction:
    """Algorithm 1, literally: returns after the first graph it starts or fails on."""
    for g in graphs:  # 2
        d = q.deployment_information(g)  # 3
        if d is not None:  # 4
            fixed = q.fixed_platform(d)
            if fixed is not None:  # 5
                p = fixed  # 6
                if (yield Start(g, p)):  # 7
                    return  # 8 success
                yield RaiseError(DEPLOYMENT_FAILED, g, p)  # 10
                return  # 11
            c = q.constraints(d)  # 13
            validity = check_validity(c, q.platform_states(), g, checks=q.checks)  # 14
            acceptable = validity.acceptable
            if acceptable:  # 15
                if not any(p in acceptable for p in q.deployed_on(g)):  # 16
                    pk = acceptable[0]
                    if (yield Start(g, pk)):  # 17
                        return  # 18
                    yield RaiseError(DEPLOYMENT_FAILED, g, pk)  # 20
                    return  # 21
                # already deployed on an acceptable platform: the loop goes on
            else:
                yield RaiseError(NO_ACCEPTABLE_PLATFORMS, g, None, validity.explain())  # 23
                return  # 24
        else:
            yield RaiseError(DEPLOYMENT_INFORMATION_MISSING, g)  # 26
            return  # 27


def paper_check_deployment(p_i: str, q: QueryPort) -> Reaction:
    """Algorithm 2, literally: returns after the first active deployment it decides on."""
    for d in q.active_deployments(p_i):  # 2-3
        g = q.perception_graph(d)  # 4
        spec = q.deployment_information(g)
        c = q.constraints(spec) if spec is not None else ()  # 5
        validity = check_validity(c, q.platform_states(), g, checks=q.checks)  # 6
        acceptable = validity.acceptable
        if not acceptable:  # 7
            yield RaiseError(NO_ACCEPTABLE_PLATFORMS, g, None, validity.explain())  # 8
            if (yield Stop(g, p_i)):  # 9
                return  # 10
            yield RaiseError(STOPPING_FAILED, g, p_i)  # 12
            return  # 13
        if p_i in acceptable:  # 14
            return  # 15
        if acceptable and p_i not in acceptable:  # 16
            pk = acceptable[0]
            if (yield Start(g, pk)):  # 17
                return  # 18
            yield RaiseError(DEPLOYMENT_FAILED, g, pk)  # 20
            return  # 21


# ----------------------------------------------------------------------------------
# desmon: corrected
# ----------------------------------------------------------------------------------
def ensure_deployed(g: str, q: QueryPort, *, make_before_break: bool = False) -> Placement:
    """Leave exactly one instance of ``g`` on a valid platform, or raise an error.

    Keeps a valid running instance (no needless migration), stops every other
    instance first (break-before-make), then tries acceptable platforms in preference
    order until a start succeeds. Returns True iff ``g`` ends up deployed validly.
    ``make_before_break`` exists only for the seeded mutant of the checker's tests.

    It is :func:`_survey` (the reads) followed by :func:`_act_on` (the commands); the
    corrected reaction calls the two halves itself so that a graph which is simply
    kept costs no generator (see :func:`_kept`).
    """
    return (yield from _act_on(g, q, _survey(g, q), make_before_break))


#: What :func:`ensure_deployed` reads before it acts: the specification (None if
#: missing), the acceptable platforms in preference order, the running instance to
#: keep (None if no instance runs on an acceptable platform), the other instances.
Survey = tuple[DeploymentSpec | None, tuple[str, ...], str | None, list[str]]


def _survey(g: str, q: QueryPort, triggers: frozenset[str] | None = None) -> Survey:
    """The facts :func:`ensure_deployed` decides on (reads only, no command).

    ``triggers`` are the platforms whose facts changed in this reaction (None: the
    context changed, or no restriction). A valid deployment of a rebalancing graph moves
    only when the best platform beats its own by more than ``min_gain`` *and* one of the
    two is among the triggers: a move answers a change, so with nothing changed nothing
    moves, and a move whose start failed is retried at the next change of either
    platform, not at every reaction (the rule upgrades follow too)."""
    spec = q.deployment_information(g)
    if spec is None:
        return None, (), None, []
    validity = validity_for(q, spec, reasons=False)
    acceptable = validity.acceptable
    keep: str | None = None
    stale: list[str] = []
    for p in q.deployed_on(g):
        if keep is None and p in acceptable:
            keep = p  # the first running instance on an acceptable platform
        elif p != keep:
            stale.append(p)
    if (
        keep is not None
        and spec.rebalance is not None
        and (triggers is None or keep in triggers or (acceptable and acceptable[0] in triggers))
        and validity.gain(keep) > spec.rebalance
    ):
        # rebalancing with hysteresis: a better platform beats this one by more than the
        # threshold, so the instance moves (stopped first, then placed best-first)
        stale.insert(0, keep)
        keep = None
    return spec, acceptable, keep, stale


def _kept(survey: Survey) -> bool:
    """True when :func:`_act_on` would yield nothing and return True: a valid instance
    runs and no other instance does (so there is nothing to stop or start)."""
    return survey[2] is not None and not survey[3]


def _act_on(g: str, q: QueryPort, survey: Survey, make_before_break: bool) -> Placement:
    """The commands of :func:`ensure_deployed` for ``g``, given its :func:`_survey`."""
    spec, acceptable, keep, stale = survey
    if spec is None:
        yield RaiseError(DEPLOYMENT_INFORMATION_MISSING, g)
        return False
    if not make_before_break:
        for p in stale:
            if not (yield Stop(g, p)):
                yield RaiseError(STOPPING_FAILED, g, p)
                return False
    if keep is not None:
        return True
    if not acceptable:
        fixed = q.fixed_platform(spec)
        explained = validity_for(q, spec).explain()
        detail = explained if fixed is None else f"fixed platform {fixed}: {explained}"
        yield RaiseError(NO_ACCEPTABLE_PLATFORMS, g, fixed, detail)
        return False
    for pk in acceptable:
        if (yield Start(g, pk)):
            if make_before_break:
                for p in stale:
                    if not (yield Stop(g, p)):
                        yield RaiseError(STOPPING_FAILED, g, p)
            return True
        yield RaiseError(DEPLOYMENT_FAILED, g, pk)
    return False


# ----------------------------------------------------------------------------------
# the selector-facing reaction
# ----------------------------------------------------------------------------------
@dataclass(frozen=True, slots=True)
class Deployer:
    """A named deployer variant: how to react to a context change and to platform changes.

    ``react(q, slots, changed, context_changed)`` returns the reaction generator. The
    remaining fields describe the variant for reports and the mutant tests.
    """

    name: str
    description: str
    react: Callable[[QueryPort, tuple[tuple[str, ...], ...], tuple[str, ...], bool], Reaction]
    #: False for a variant whose selector knows no fallbacks (the paper's): it is asked,
    #: and judged by ``coverage``, for the first graph of each slot only.
    fallbacks: bool = True
    #: True only for the seeded mutant with stale error semantics: an error
    #: stands for a graph while it is wanted and not validly active, even when another
    #: alternative serves its slot (see :func:`desmon.deployment.core.standing_after`).
    stale_errors: bool = False

    def __post_init__(self) -> None:
        """Each field of its type: a flag given as text (``fallbacks="no"``, which is true)
        would silently mean the other variant."""
        if not isinstance(self.name, str) or not self.name.strip() or not self.name.isprintable():
            raise ModelError(f"Deployer(...) name {self.name!r}: give a non-empty name on one line, e.g. 'my-deployer'")
        check_text("Deployer(...) description", self.description)
        check_flag("Deployer(...) fallbacks", self.fallbacks)
        check_flag("Deployer(...) stale_errors", self.stale_errors)

    def requested(self, slots: tuple[tuple[str, ...], ...]) -> tuple[tuple[str, ...], ...]:
        """The slots as this variant's selector requests them."""
        return slots if self.fallbacks else tuple(slot[:1] for slot in slots)


def _stop_graphs(graphs: Iterable[str], q: QueryPort) -> Reaction:
    for g in graphs:
        for p in q.deployed_on(g):
            if not (yield Stop(g, p)):
                yield RaiseError(STOPPING_FAILED, g, p)


def _active_graphs(q: QueryPort) -> list[str]:
    """The graphs active anywhere, sorted."""
    deployments = q.deployments()
    return sorted({g for g, _p in deployments}) if deployments else []


def _named_in(slots: tuple[tuple[str, ...], ...]) -> frozenset[str]:
    return frozenset(g for slot in slots for g in slot)


def _wanted_by(slots: tuple[tuple[str, ...], ...], q: QueryPort) -> frozenset[str]:
    """Every graph named in ``slots``; interned on the run's memo when ``q``'s checks keep
    one (slots are few and immutable)."""
    checks = q.checks
    if type(checks) is not MemoChecks:
        return _named_in(slots)
    known = checks.values("wanted")
    wanted = known.get(slots)
    if wanted is None:
        wanted = known.keep(slots, _named_in(slots))
    return wanted  # type: ignore[no-any-return]


def _paper_react(
    q: QueryPort, slots: tuple[tuple[str, ...], ...], changed: tuple[str, ...], context_changed: bool
) -> Reaction:
    # The paper's selector has no fallbacks: it requests the first graph of each slot.
    wanted = [slot[0] for slot in slots]
    if context_changed:
        # "The selector requests the deployer to stop the current slip detector and to deploy ..."
        yield from _stop_graphs([g for g in _active_graphs(q) if g not in wanted], q)
        yield from paper_deploy(wanted, q)
    for p in changed:
        yield from paper_check_deployment(p, q)


#: Upgrade policies of the corrected deployer (see :func:`make_desmon_react`).
BREAK_BEFORE_MAKE = "break-before-make"
KEEP_FALLBACK = "keep-fallback"
UPGRADE_POLICIES = (BREAK_BEFORE_MAKE, KEEP_FALLBACK)


def fits_if_freed(g: str, spec: DeploymentSpec, q: QueryPort, freed: list[str]) -> tuple[str, ...]:
    """The platforms acceptable for ``g`` if the running ``freed`` graphs were stopped
    (Capacity is the only requirement their stop can change)."""
    world = states = q.platform_states()
    fixed = q.fixed_platform(spec)
    if fixed is not None:
        states = tuple(s for s in states if s.name == fixed)
    return spec_validity(q.constraints(spec), spec.reads, states, world, (g, *freed), reasons=False, checks=q.checks).acceptable


def _reads_from(spec: DeploymentSpec | None, platforms: tuple[str, ...] | frozenset[str]) -> bool:
    """Does a graph of ``spec`` read a device hosted on one of ``platforms``?"""
    return spec is not None and any(h in platforms for r in spec.reads for h in r.hosts)


def _recheck(
    q: QueryPort, changed: tuple[str, ...], placed: dict[str, bool], make_before_break: bool, triggers: frozenset[str] | None = None
) -> Reaction:
    """Corrected Algorithm 2: every deployment on a ``changed`` platform, and every one
    that reads a device hosted on a changed platform, is kept if still valid, else
    migrated, else stopped with an error; each graph's outcome goes to ``placed``.

    Placing a graph is ensure_deployed, written out as its two halves so that a graph
    that is simply kept (the common case) creates no generator.
    """
    for p in changed:
        for d in q.active_deployments(p):
            g = q.perception_graph(d)
            if g not in placed:
                survey = _survey(g, q, triggers)
                placed[g] = True if _kept(survey) else (yield from _act_on(g, q, survey, make_before_break))
    for g, _p in q.deployments():  # the readers of a changed platform's devices
        if g not in placed and _reads_from(q.deployment_information(g), changed):
            survey = _survey(g, q, triggers)
            placed[g] = True if _kept(survey) else (yield from _act_on(g, q, survey, make_before_break))


def _place_slots(
    q: QueryPort,
    slots: tuple[tuple[str, ...], ...],
    changed: tuple[str, ...],
    placed: dict[str, bool],
    make_before_break: bool,
    upgrading: bool,
    triggers: frozenset[str] | None = None,
    context_changed: bool = False,
) -> Generator[Command, "bool | None", set[str]]:
    """Corrected Algorithm 1: place one graph of every slot (the first alternative that
    can be placed, each graph decided once per reaction); return the graphs chosen."""
    chosen: set[str] = set()
    for slot in slots:
        for i, g in enumerate(slot):
            ok = placed.get(g)
            if ok is None:
                survey = _survey(g, q, triggers)
                spec = survey[0]
                if upgrading and spec is not None and not survey[1] and i + 1 < len(slot):
                    survey = yield from _upgrade(g, spec, slot[i + 1:], survey, q, changed, placed, context_changed)
                ok = placed[g] = True if _kept(survey) else (yield from _act_on(g, q, survey, make_before_break))
            if ok:
                chosen.add(g)
                break
    return chosen


def _upgrade(
    g: str,
    spec: DeploymentSpec,
    fallbacks: tuple[str, ...],
    survey: Survey,
    q: QueryPort,
    changed: tuple[str, ...],
    placed: dict[str, bool],
    context_changed: bool = False,
) -> Generator[Command, "bool | None", Survey]:
    """The upgrade: a running fallback of this slot may be all that blocks ``g``.

    If stopping the running ``fallbacks`` would make ``g`` acceptable somewhere, and this
    reaction answers a change that may have made it so (:func:`upgrade_due`: the context
    changed, or a platform where ``g`` would then fit or whose devices ``g`` reads
    changed), stop them (break before make), forget their decisions (they are decided
    again if ``g`` cannot be placed) and return ``g``'s new survey; else ``survey``.
    """
    freed = [f for f in fallbacks if q.deployed_on(f)]
    if freed and (context_changed or changed) and upgrade_due(spec, fits_if_freed(g, spec, q, freed), changed, context_changed):
        yield from _stop_graphs(freed, q)  # break before make
        for f in freed:
            placed.pop(f, None)
        return _survey(g, q)
    return survey


def upgrade_due(spec: DeploymentSpec, fits: tuple[str, ...], changed: tuple[str, ...] | frozenset[str], context_changed: bool) -> bool:
    """The upgrade rule (docs/design.md §8), one definition for the deployer and the
    ``preferred-when-possible`` invariant: the preferred alternative of ``spec``, which
    would be acceptable on ``fits`` with its slot's running fallbacks stopped, is due a
    try in a reaction to a context change, or to a change of a platform where it would
    fit or whose devices it reads. A start refused or failed since is not retried until
    one of those changes again."""
    if not fits:
        return False
    return context_changed or any(p in changed for p in fits) or _reads_from(spec, changed)


def make_desmon_react(
    *, make_before_break: bool = False, upgrade: str = BREAK_BEFORE_MAKE, free_first: bool = True
) -> Callable[[QueryPort, tuple[tuple[str, ...], ...], tuple[str, ...], bool], Reaction]:
    """Build the corrected reaction (``make_before_break`` and ``free_first=False`` exist
    for the checker's seeded mutants).

    What the context no longer wants is stopped first (its room may be needed); then
    corrected Algorithm 2: every deployment on a changed platform is re-checked (kept if
    still valid, else migrated break-before-make, else stopped with an error); then corrected Algorithm 1 places
    one graph of every slot (the first alternative that can be placed), each graph
    decided once per reaction; unneeded fallbacks are stopped last.

    ``upgrade`` says what happens when a slot is served by a fallback and its preferred
    alternative has no acceptable platform only because the running fallbacks hold the
    capacity: ``"break-before-make"`` (default) stops those fallbacks, then places the
    preferred alternative, and places the fallback again if that fails (the robot is
    blind from the stop until the preferred detector is warm); ``"keep-fallback"``
    keeps the fallback running (no blind time, but the preferred detector never returns
    while the fallback holds its room). An upgrade is attempted when :func:`upgrade_due`
    says so: in a reaction to a context change, or to a change of a platform where the
    preferred alternative would then fit or whose devices it reads; a start that failed
    is retried at the next such change, not at every reaction.
    """
    if upgrade not in UPGRADE_POLICIES:
        raise ModelError(f"unknown upgrade policy {upgrade!r}: choose one of {', '.join(UPGRADE_POLICIES)}")
    upgrading = upgrade == BREAK_BEFORE_MAKE

    def react(
        q: QueryPort, slots: tuple[tuple[str, ...], ...], changed: tuple[str, ...], context_changed: bool
    ) -> Reaction:
        placed: dict[str, bool] = {}  # each graph is decided once per reaction
        tried: dict[str, set[str]] = {}  # the platforms each graph's starts were issued on
        yield from _noting_starts(body(q, slots, changed, context_changed, placed), tried)
        if not all(any(placed.get(g) for g in slot) for slot in slots):
            yield from _second_chance(q, slots, placed, tried)

    def body(
        q: QueryPort, slots: tuple[tuple[str, ...], ...], changed: tuple[str, ...], context_changed: bool, placed: dict[str, bool]
    ) -> Reaction:
        triggers = None if context_changed else frozenset(changed)  # what a rebalancing move may answer
        wanted = _wanted_by(slots, q)
        if changed and not free_first:
            yield from _recheck(q, changed, placed, make_before_break, triggers)
        # Free what the context no longer wants first: its capacity may be needed, by the
        # re-checked graphs too (one reaction may answer a context change and a platform's)
        unwanted = [g for g in _active_graphs(q) if g not in wanted]
        if unwanted:
            yield from _stop_graphs(unwanted, q)
        if changed and free_first:
            yield from _recheck(q, changed, placed, make_before_break, triggers)
        chosen = yield from _place_slots(q, slots, changed, placed, make_before_break, upgrading, triggers, context_changed)
        # Fallbacks that are no longer needed (a better alternative is placed again).
        unneeded = [g for g in _active_graphs(q) if g in wanted and g not in chosen]
        if unneeded:
            yield from _stop_graphs(unneeded, q)

    return react


def _noting_starts(reaction: Reaction, tried: dict[str, set[str]]) -> Reaction:
    """``reaction``, passed through, noting in ``tried`` the platform of every start."""

    def note(cmd: Command) -> None:
        if type(cmd) is Start:
            tried.setdefault(cmd.graph, set()).add(cmd.platform)

    return relay(reaction, before=note)


def _second_chance(q: QueryPort, slots: tuple[tuple[str, ...], ...], placed: dict[str, bool], tried: dict[str, set[str]]) -> Reaction:
    """A slot still unserved at the end of the reaction, whose alternatives were decided
    before a later stop freed room (a re-checked graph stopped after them, an unneeded
    fallback): each alternative that failed and does not run is started on the platforms
    that are acceptable now and were not tried in this reaction, in preference order.
    Without it an error would stand while an acceptable platform is left untried
    (``errors-justified``, docs/design.md §7)."""
    for slot in slots:
        if any(placed.get(g) for g in slot):
            continue
        for g in slot:
            if placed.get(g) is not False or q.deployed_on(g):
                continue
            spec = q.deployment_information(g)
            if spec is None:
                continue
            done = tried.get(g, ())
            for p in validity_for(q, spec, reasons=False).acceptable:
                if p in done:
                    continue
                if (yield Start(g, p)):
                    placed[g] = True
                    break
                yield RaiseError(DEPLOYMENT_FAILED, g, p)
            if placed.get(g):
                break


PAPER = Deployer("paper", "Algorithms 1 and 2 of the paper, transcribed literally", _paper_react, fallbacks=False)
DESMON = Deployer("desmon", "the corrected deployer (docs/findings.md); upgrades to a preferred alternative break-before-make", make_desmon_react())
DESMON_KEEP_FALLBACK = Deployer(
    "desmon-keep-fallback",
    "the corrected deployer with upgrade policy keep-fallback: a running fallback is kept even when the preferred alternative would fit without it",
    make_desmon_react(upgrade=KEEP_FALLBACK),
)

#: Deployer variants selectable by name.
DEPLOYERS: dict[str, Deployer] = {d.name: d for d in (PAPER, DESMON, DESMON_KEEP_FALLBACK)}


def get_deployer(name: str | Deployer) -> Deployer:
    """The deployer variant called ``name``; a ModelError lists the valid names."""
    if isinstance(name, Deployer):
        return name
    try:
        return DEPLOYERS[name]
    except KeyError:
        raise ModelError(f"unknown deployer {name!r}: choose one of {', '.join(DEPLOYERS)}") from None
