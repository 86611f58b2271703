"""What one robot's SimPy world accounts for: the audit of the named invariants, and the
metrics of docs/design.md §10 at the horizon (:func:`robot_metrics`), read off the
robot's parts and its :class:`~desmon.sim.books.Books` (re-exported here).

:func:`audit` checks the named invariants on a view of the live repository at a
quiescent point.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from desmon.deployment.invariants import INSTANT_INVARIANTS, SystemView, check_invariants, get_invariants, start_findings
from desmon.sim.books import Books
from desmon.sim.metrics import slip_metrics

if TYPE_CHECKING:
    from desmon.sim.robot import RobotParts

__all__ = ["Books", "audit", "robot_metrics"]


def audit(
    parts: "RobotParts", view: SystemView, after: str = "", skip: frozenset[str] = frozenset(), started: tuple[str, str] | None = None,
) -> tuple[str, ...]:
    """The named invariants on ``view`` (of the live repository) at a quiescent point, each
    violation booked unless its invariant is in ``skip`` (booked already in this reaction),
    or, ``after`` a start inside a reaction (``"start g on p"``, ``started``: (g, p)), the instantaneous ones
    (:data:`~desmon.deployment.invariants.INSTANT_INVARIANTS`) that start broke, as the
    checker watches them (:func:`~desmon.deployment.invariants.start_findings`). Returns
    the names booked."""
    books = parts.books
    if not after:
        books.audits += 1
    now = parts.env.now
    booked: list[str] = []
    found = start_findings(view, get_invariants(INSTANT_INVARIANTS), *started) if started is not None else check_invariants(view)
    stale: list[str] | None = None
    for name, msg in found:
        if name not in skip:
            if stale is None:
                stale = unnoticed(parts, view)
            where = f" (during the reaction, right after `{after}`)" if after else ""
            if stale:  # (the checker notices every change at once: it has no such state)
                where += f" (while the monitor had not yet noticed: {', '.join(stale)}; docs/design.md §6)"
            books.violation(now, name, msg + where)
            booked.append(name)
    return tuple(booked)


def unnoticed(parts: "RobotParts", view: SystemView) -> list[str]:
    """The changes of the world the monitor has not noticed yet (its ``heartbeat_timeout``):
    each platform of ``view`` (the repository's facts) up or down in fact but not in the
    repository, each device of them working or failed in fact but not there."""
    facts = parts.facts
    out: list[str] = []
    working: dict[str, set[str]] = {}
    for s in view.states:
        up = facts.up.get(s.name)
        if up is not None and up != s.up:
            out.append(f"platform {s.name} {'up' if up else 'down'}")
        working[s.name] = {d.name for d in s.devices}
    for device, ok in facts.dev_ok.items():
        believed = working.get(facts.host[device])
        if believed is not None and ok != (device in believed):
            out.append(f"device {device} {'repaired' if ok else 'failed'}")
    return out


def robot_metrics(parts: "RobotParts") -> dict[str, Any]:
    """The metrics of one robot's run at the horizon (docs/design.md §10)."""
    ex = parts.exposure
    books = parts.books
    infra = parts.infra
    by_kind: dict[str, int] = {}
    for e in books.errors:
        by_kind[e.kind] = by_kind.get(e.kind, 0) + 1
    m: dict[str, Any] = {
        "horizon_s": parts.horizon,
        "risky_time_s": round(ex.risky, 6),
        "unmonitored_exposure_s": round(ex.exposure, 6),
        "unmonitored_by_cause_s": {c: round(v, 6) for c, v in ex.by_cause.items()},
        "excluded_s": round(ex.excluded, 6),
        "switches": ex.switches,
        # a run with no switch has no blind time per switch (None, as a latency with no slip
        # detected); its longest blind time is 0: no switch left the robot blind
        "blind_time_per_switch_s": round(sum(ex.blind) / len(ex.blind), 6) if ex.blind else None,
        "blind_time_max_s": round(max(ex.blind), 6) if ex.blind else 0.0,
        "reactions": books.reactions,
        "starts": infra.starts,
        "start_failures": infra.start_failures,
        "stops": infra.stops,
        "migrations": books.migrations,
        "upgrades": books.upgrades,
        "upgrades_failed": books.upgrades_failed,
        "upgrade_blind_s": round(books.upgrade_blind, 6),
        "errors": dict(sorted(by_kind.items())),
        "violations": len(books.violations),
        "memory_peak_mb": {p: round(v, 3) for p, v in parts.memory.peak.items()},
        "overcommit_s": {p: round(v, 6) for p, v in sorted(parts.memory.over.items()) if v > 0},
        "alarms": len(infra.alarms),
        "signals": parts.signals,
    }
    world = parts.world
    if world.changes or world.random_changes is not None or world.lease is not None:
        m["requirement_changes"] = books.requirement_changes
        m["leases"] = books.leases
        m["leased_s"] = round(books.leased_s, 6)
    # graphs that cannot detect a slip: never counted as watching (Infrastructure.activate)
    m["no_signal_model"] = {
        g: list(kinds) for g, kinds in world.no_signal_model(parts.model.graphs).items() if world.given_rate(g) is None
    }
    m["given_detection_rates"] = dict(world.detection_rates)
    if parts.signals:
        m.update(slip_metrics(parts.truth.slips, infra.alarms))
        bank = parts.truth.bank
        m["samples"] = dict(bank.samples) if bank is not None else {}
    else:
        m["slips_injected"] = len(parts.truth.slips)
    return m
