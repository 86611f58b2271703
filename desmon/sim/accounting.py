"""What one robot's SimPy world counts: reactions, migrations, upgrades, decisions,
errors, the audit's violations, leases, and the metrics of docs/design.md §10 at the
horizon (:func:`robot_metrics`).

:class:`Books` only records; the deployer driver (:mod:`desmon.sim.driver`) and the
processes (:mod:`desmon.sim.processes`) tell it what happened. :func:`audit` checks the
named invariants on a view of the live repository at a quiescent point.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from desmon.deployment.invariants import SystemView, check_invariants
from desmon.deployment.ports import ErrorRecord
from desmon.sim.metrics import slip_metrics
from desmon.sim.trace import Trace

if TYPE_CHECKING:
    from desmon.sim.parts import RobotParts

__all__ = ["Books", "audit", "robot_metrics"]


class Books:
    """The counters and records of one robot's run (the infrastructure keeps its own
    starts and stops). ``keep_decisions`` False: decisions go to the trace only."""

    def __init__(self, trace: Trace, keep_decisions: bool = True) -> None:
        self.trace = trace
        self.keep_decisions = keep_decisions
        self.decisions: list[dict[str, Any]] = []
        self.errors: list[ErrorRecord] = []
        self.violations: list[tuple[float, str, str]] = []
        self.reactions = self.audits = self.migrations = 0
        self.history_edges = 0
        #: upgrades back to a preferred alternative (break-before-make), failed ones, and
        #: the seconds their slots went unserved (stop of the fallback -> ready)
        self.upgrades = self.upgrades_failed = 0
        self.upgrade_blind = 0.0
        #: run-time changes: requirement changes applied, leases (requested, joined), leased seconds
        self.requirement_changes = self.leases = 0
        self.leased_s = 0.0
        self.leased: dict[str, float] = {}  # on-demand platform -> join time, while leased
        self.lease_requested: set[str] = set()

    def count_history(self, change: Any) -> None:
        """A DEPLOYMENT_HISTORY edge was written (the repository's subscription)."""
        self.history_edges += 1

    def violation(self, t: float, name: str, msg: str) -> None:
        self.violations.append((t, name, msg))
        self.trace.emit(t, "violation", invariant=name, message=msg)

    def decision(self, now: float, what: str, graph: str, platform: str, ok: bool, issued: float, why: str) -> None:
        if self.keep_decisions:
            rounded = self.trace.rounded  # round(float(x), 6): for a float the same as round(x, 6)
            rec = {
                "t": rounded(now) if type(now) is float else round(now, 6),
                "issued": rounded(issued) if type(issued) is float else round(issued, 6),
                "command": what, "graph": graph, "platform": platform, "ok": ok,
            }
            if why:
                rec["why"] = why
            self.decisions.append(rec)
        self.trace.emit(now, "decision", command=what, graph=graph, platform=platform, ok=ok, issued=issued, why=why)

    def count_upgrade(
        self, graph: str, ready: float, slots: tuple[tuple[str, ...], ...], stopped_at: dict[str, float], tried: set[str]
    ) -> None:
        """``graph`` (valid from ``ready``) started in a reaction that stopped a wanted
        alternative of its slot: an upgrade if ``graph`` is preferred to the stopped one;
        a failed upgrade if a preferred alternative's start failed in between and a
        fallback is placed again. Either way the slot went unserved from that stop until
        the started detector is ready: the upgrade's blind time. (A fallback that simply
        migrates is neither.)"""
        for slot in slots:
            if graph not in slot:
                continue
            mine = slot.index(graph)
            gone = [(slot.index(f), t) for f, t in stopped_at.items() if f in slot]
            if not gone:
                continue
            if any(i > mine for i, _t in gone):
                self.upgrades += 1
            elif any(slot.index(h) < min(i for i, _t in gone) for h in tried if h in slot):
                self.upgrades_failed += 1
            else:
                return
            if math.isfinite(ready):
                self.upgrade_blind += ready - min(t for _i, t in gone)
            for f in [f for f in stopped_at if f in slot]:
                del stopped_at[f]
            return

    def lease_joined(self, platform: str, now: float) -> None:
        self.leased.setdefault(platform, now)

    def lease_left(self, platform: str, now: float) -> None:
        if platform in self.leased:
            self.leased_s += now - self.leased.pop(platform)

    def close_leases(self, now: float) -> None:
        for _platform, since in self.leased.items():
            self.leased_s += now - since


def audit(parts: "RobotParts", view: SystemView) -> None:
    """The named invariants on ``view`` (of the live repository), at a quiescent point."""
    books = parts.books
    books.audits += 1
    now = parts.env.now
    for name, msg in check_invariants(view):
        books.violation(now, name, msg)


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
        "blind_time_per_switch_s": round(sum(ex.blind) / len(ex.blind), 6) if ex.blind else 0.0,
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
