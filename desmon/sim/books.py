"""What one robot's SimPy world counts: reactions, migrations, upgrades, decisions,
errors, the audit's violations and leases.

:class:`Books` only records; the deployer driver (:mod:`desmon.sim.driver`), the
processes (:mod:`desmon.sim.processes`) and the audit (:mod:`desmon.sim.accounting`)
tell it what happened, and :func:`~desmon.sim.accounting.robot_metrics` reads it at
the horizon.
"""

from __future__ import annotations

import math
from typing import Any

from desmon.deployment.ports import ErrorRecord
from desmon.sim.trace import Trace

__all__ = ["Books"]


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
