"""The deployer driver of one robot's SimPy world: the process that runs the pure core.

The robot's :class:`~desmon.sim.inbox.Inbox` (re-exported here) collects what the
repository's Notify subscription (or a fleet's router) reports and wakes the driver.
:func:`deployer` takes it as a stimulus and drives ``core.reaction``: each
``Start`` is executed by the Control infrastructure (latency, outcome), ``Stop`` at
once, ``RaiseError`` is stamped with ``env.now``. After every start that succeeded the
instantaneous invariants are audited (on what it changed), after every reaction ``core.settle``
and, when no newer fact is pending, all the named invariants (``audit``). No decision is
made here.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Callable

from desmon.deployment.core import not_a_command, stamp
from desmon.deployment.guard import DeployerFault
from desmon.deployment.invariants import INSTANT_INVARIANTS
from desmon.deployment.ports import NO_ACCEPTABLE_PLATFORMS, RaiseError, Start, Stop
from desmon.sim.inbox import Inbox
from desmon.sim.infrastructure import RANDOM_FAILURE, SCRIPTED_FAILURE
from desmon.sim.processes import maybe_lease

if TYPE_CHECKING:
    from desmon.sim.robot import RobotParts

__all__ = ["Inbox", "deployer", "Audit"]

#: ``audit(after, skip, started)``: the named invariants at a quiescent point (``after``
#: empty, ``started`` None), or the instantaneous ones the start of ``started`` (graph,
#: platform) broke inside a reaction (``after``: ``"start g on p"``), each booked unless in
#: ``skip``; returns the names it booked (:func:`desmon.sim.accounting.audit`)
Audit = Callable[[str, frozenset[str], "tuple[str, str] | None"], tuple[str, ...]]


class _Reaction:
    """What the deployer process books during one reaction (a plain class: one per reaction)."""

    __slots__ = ("slots", "raised", "stopped_here", "stopped_at", "tried", "broken", "start_failed")

    def __init__(self, slots: tuple[tuple[str, ...], ...]) -> None:
        self.slots = slots
        self.raised: list[str] = []
        self.stopped_here: dict[str, str] = {}
        self.stopped_at: dict[str, float] = {}  # wanted slot members stopped in this reaction
        self.tried: set[str] = set()  # graphs whose start failed in this reaction
        #: the instantaneous invariants booked inside this reaction, each at its first
        #: violation (the checker's transition carries the same with ``verify --continue``)
        self.broken: frozenset[str] = frozenset()
        self.start_failed = False  # whether a start the Control rules allowed failed in this reaction (the start-failure model)


def deployer(parts: RobotParts, audit: Audit):  # type: ignore[no-untyped-def]
    """The deployer's process: one reaction per stimulus, ``audit`` after every start that
    succeeds and at every quiescent point."""
    env = parts.env
    inbox = parts.inbox
    books = parts.books
    core = parts.core
    while True:
        if not inbox.pending():
            inbox.wake = env.event()
            yield inbox.wake
            inbox.wake = None
        stim = inbox.take()
        books.reactions += 1
        ctx = parts.query.context()
        parts.trace.emit(env.now, "reaction", context=ctx, changed=list(stim.changed_platforms), context_changed=stim.context_changed)
        book = _Reaction(core.slots())  # what this reaction serves, even if the context moves on meanwhile
        yield from _drive(parts, core.reaction(stim), book, audit)
        core.settle(book.raised)
        quiescent = not inbox.pending()
        for name, msg in core.findings:  # transition properties (no-flapping, errors-justified, ...)
            # the others judge the reaction on the facts it left: only at a quiescent point
            if name == "no-flapping" or quiescent:
                books.violation(env.now, name, msg)
        if quiescent:
            audit("", book.broken, None)


def _drive(parts: RobotParts, reaction: Any, book: _Reaction, audit: Audit):  # type: ignore[no-untyped-def]
    """Execute the commands of one reaction, sending each outcome back; ``audit`` the
    instantaneous invariants after each start that succeeded (a stop breaks none of them:
    :func:`~desmon.deployment.invariants.start_findings`)."""
    outcome: bool | None = None
    while True:
        try:
            cmd = reaction.send(outcome)
        except StopIteration:
            return
        except DeployerFault as fault:  # where in the run: the first reaction means it cannot run at all,
            # unless a start of it had failed (then it failed in a state the run reached, as the checker says)
            fault.initial = parts.books.reactions == 1 and not book.start_failed
            fault.args = (f"at t={parts.env.now:g} s, {fault.args[0]}",)
            raise
        if isinstance(cmd, Start):
            restart = (cmd.graph, cmd.platform) in parts.facts.instances  # (a no-op: it changes nothing to audit)
            outcome = yield from _command_start(parts, cmd, book)
            if outcome and not restart and len(book.broken) < len(INSTANT_INVARIANTS):
                book.broken |= frozenset(audit(f"start {cmd.graph} on {cmd.platform}", book.broken, (cmd.graph, cmd.platform)))
        elif isinstance(cmd, Stop):
            outcome = _command_stop(parts, cmd, book)
        elif isinstance(cmd, RaiseError):
            outcome = None
            _command_error(parts, cmd, book)
        else:
            raise not_a_command(cmd)


def _command_start(parts: RobotParts, cmd: Start, book: _Reaction):  # type: ignore[no-untyped-def]
    """Execute a Start of the reaction (latency, outcome) and count what it means."""
    issued = parts.env.now
    res = yield from parts.infra.start(cmd.graph, cmd.platform)
    outcome = res is True
    books = parts.books
    instances = parts.facts.instances
    elsewhere = [p for (g, p) in instances if g == cmd.graph and p != cmd.platform]
    if outcome and (elsewhere or book.stopped_here.get(cmd.graph, cmd.platform) != cmd.platform):
        books.migrations += 1
    if outcome and book.stopped_at:
        books.count_upgrade(cmd.graph, instances[(cmd.graph, cmd.platform)].valid_from, book.slots, book.stopped_at, book.tried)
    elif not outcome:
        book.tried.add(cmd.graph)
        book.start_failed = book.start_failed or str(res) in (SCRIPTED_FAILURE, RANDOM_FAILURE)
    books.decision(parts.env.now, "start", cmd.graph, cmd.platform, outcome, issued, "" if outcome else str(res))
    return outcome


def _command_stop(parts: RobotParts, cmd: Stop, book: _Reaction) -> bool:
    now = parts.env.now
    outcome = parts.infra.stop(cmd.graph, cmd.platform)
    if outcome:
        book.stopped_here[cmd.graph] = cmd.platform
        if any(cmd.graph in slot and len(slot) > 1 for slot in book.slots):
            book.stopped_at[cmd.graph] = now
    parts.books.decision(now, "stop", cmd.graph, cmd.platform, outcome, now, "")
    return outcome


def _command_error(parts: RobotParts, cmd: RaiseError, book: _Reaction) -> None:
    now = parts.env.now
    rec = stamp(cmd, now)
    parts.books.errors.append(rec)
    book.raised.append(cmd.graph)
    parts.trace.emit(now, "error", kind=rec.kind, graph=rec.graph, platform=rec.platform, detail=rec.detail)
    if cmd.kind == NO_ACCEPTABLE_PLATFORMS and parts.world.lease is not None:
        maybe_lease(parts, cmd.graph)
