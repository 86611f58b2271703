"""The SimPy world of one robot: robot, sensors, platforms, fault injector, context
monitor, infrastructure (the Control port) and the deployer's process, with the audit.

:class:`SimWorld` assembles the parts of :mod:`desmon.sim.parts` on its own environment
and repository and runs them:

* the physical facts and ground truth (:mod:`desmon.sim.facts`): platforms up, loads,
  devices, running instances; the task's segments, the slips and the sensor bank;
* the Control infrastructure (:mod:`desmon.sim.infrastructure`): starts (latency, then
  success or failure by the world's failure model only -- Capacity is the core's
  decision, and the ``no-overcommit`` audit reports an over-commitment), stops, and the
  detector processes (which wake on the ``world.block`` grid around ground-truth slips,
  ``SLIP_WINDOW``, and every ``world.quiet_block`` seconds elsewhere);
* the processes (:mod:`desmon.sim.processes`): the robot walking the task's segments
  (each new action observed and interpreted after the recognition delay), the context
  monitor inserting facts through the core's Insert port (failures noticed after the
  heartbeat timeout), the fault injector, loads, run-time changes and leases;
* the deployer driver (:mod:`desmon.sim.driver`), woken by the repository's Notify
  subscription, driving ``core.reaction(stimulus)``; after every reaction
  ``core.settle`` and, at a quiescent point, the named invariants are audited on the
  live repository;
* the accounting (:mod:`desmon.sim.accounting`): migrations, upgrades, decisions,
  errors, violations and the metrics.

Every process is a thin shell around the pure deployment core
(:class:`desmon.deployment.core.DeploymentCore`): it waits, reads the clock and calls
the core; no decision is made here.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass
from typing import Any, Callable, Iterable

import simpy

from desmon.deployment.guard import Guard
from desmon.deployment.ports import ErrorRecord
from desmon.deployment.run import RunContext, run_context
from desmon.deployment.validity import PlatformMemoChecks
from desmon.detectors.base import Alarm
from desmon.detectors.signals.ahead import AHEAD_MIN_S, check_render_ahead, fork_safe
from desmon.detectors.signals.tactile_array import holding_seconds
from desmon.detectors.tactile import flow_ahead
from desmon.errors import ScenarioError
from desmon.model.checks import check_number
from desmon.model.scenario import Scenario
from desmon.repository import labels as L
from desmon.repository.facts import load_model
from desmon.repository.query import RepositoryQuery
from desmon.repository.store import ADD_EDGE, REMOVE_EDGE, RELABEL_EDGE, UPDATE_NODE, Repository
from desmon.sim.accounting import audit, robot_metrics
from desmon.sim.collector import Collector, collector_relaxed
from desmon.sim.facts import SLIP_WINDOW, Instance
from desmon.sim.metrics import AUDIT, EVERY_ALARM, RECORDS, SIGNALS, work_read
from desmon.sim.parts import RobotParts, robot_parts, start_processes
from desmon.sim.processes import OBSERVATION, apply_initial, progress
from desmon.sim.streams import TactileStream
from desmon.sim.trace import Trace, declared_actions, graph_resources, initial_loads, platform_resources
from desmon.sim.world import Slip, World, world_of

__all__ = ["SimWorld", "RunResult", "simulate", "OBSERVATION", "SLIP_WINDOW", "Instance"]


@dataclass
class RunResult:
    """Everything a run produced."""

    scenario: Scenario
    world: World
    deployer: str
    seed: int
    horizon: float
    trace: Trace
    repo: Repository
    metrics: dict[str, Any]
    decisions: list[dict[str, Any]]
    errors: list[ErrorRecord]
    violations: list[tuple[float, str, str]]
    slips: tuple[Slip, ...]
    alarms: list[Alarm]
    events: int = 0


class SimWorld:
    """One simulation of a scenario (see the module docstring): the parts of
    :mod:`desmon.sim.parts` on an environment and a repository of its own."""

    def __init__(
        self,
        scenario: Scenario,
        *,
        deployer: str = "desmon",
        seed: int = 0,
        until: float | None = None,
        trace: Trace | None = None,
        signals: bool | None = None,
        progress: Callable[[float, float], None] | None = None,
        on_quiescent: "Callable[[SimWorld], None] | None" = None,
        render_ahead: bool | None = None,
        guard: Guard | None = None,
        run: RunContext | None = None,
        reads: Iterable[str] | None = None,
        collector: Collector | None = None,
    ) -> None:
        self.scenario = scenario
        #: the collector's bookkeeping this run shares with the caller's other runs (None: its own)
        self.collector = collector
        #: the run this world belongs to (:mod:`desmon.deployment.run`): its guard, and its
        #: Checks port (each platform's part memoised, no whole answer: a robot's facts
        #: change one platform at a time)
        self.run_context = run_context(run, guard).with_checks(PlatformMemoChecks, answers=False)
        #: render the tactile frames and the wrench in forked workers while the run goes on
        #: (True, False; None: where :func:`~desmon.detectors.signals.ahead.fork_safe` holds and
        #: the run has at least ``AHEAD_MIN_S`` of object in hand); the same bytes either way
        self.render_ahead = check_render_ahead(render_ahead)
        #: called with this world at every quiescent point, after its audit (a conformance
        #: harness compares the world there with the checker's state; None: nobody asks)
        self.on_quiescent = on_quiescent
        self.model = scenario.model
        self.world = world_of(scenario)
        if isinstance(seed, bool) or not isinstance(seed, numbers.Integral) or seed < 0:  # (the API's; the CLI's is argparse's)
            raise ScenarioError(f"seed {seed!r}: give a whole number, 0 or more")
        self.seed = int(seed)
        if until is not None:
            check_number("until", until, error=ScenarioError, positive=True, unit=" of simulated seconds")
        self.horizon = float(until if until is not None else self.world.horizon)
        #: the run figures (:data:`~desmon.sim.metrics.RUN_FIGURES`) the caller reads, or None:
        #: every output. A run read for some figures only skips the work no output it has
        #: needs (:func:`~desmon.sim.metrics.work_read`): the signals and detectors when no
        #: figure of the alarms is read, the audit when the violations are not, the records
        #: (the decisions, and the trace's when no trace is given), the detectors far from
        #: every slip unless ``false_alarms`` is read. The figures read are the same either way.
        self.reads = None if reads is None else frozenset(reads)
        needed = work_read(self.reads)
        self.signals_on = (self.world.signals if signals is None else bool(signals)) and SIGNALS in needed
        self._audited = AUDIT in needed or on_quiescent is not None
        self.trace = trace if trace is not None else Trace(keep=RECORDS in needed)
        self.progress = progress
        self.env = simpy.Environment()
        env = self.env
        self.repo = Repository(clock=lambda: env.now)
        load_model(self.repo, self.model)
        self.query = RepositoryQuery(self.repo, self.run_context.checks)  # the run's memoised checks, per platform
        #: the parts the processes share (facts, infrastructure, books, inbox, ...)
        self.parts: RobotParts = robot_parts(
            scenario, self.world, env=env, repo=self.repo, query=self.query, deployer=deployer, seed=self.seed,
            horizon=self.horizon, signals=self.signals_on, trace=self.trace, run=self.run_context, keep_decisions=RECORDS in needed,
            every_alarm=EVERY_ALARM in needed or trace is not None,
        )
        self.core = self.parts.core
        self.deployer_name = self.core.deployer.name
        self.infra = self.parts.infra
        self.facts = self.parts.facts
        self.books = self.parts.books
        self.instances = self.facts.instances
        self.exposure = self.parts.exposure
        self.memory = self.parts.memory
        self.decisions = self.books.decisions
        self.errors = self.books.errors
        self.violations = self.books.violations
        self.alarms = self.infra.alarms
        self.bank = self.parts.truth.bank
        self.slips = self.parts.truth.slips
        apply_initial(self.parts)
        # Notify: repository changes wake the deployer
        self.repo.subscribe(self.parts.inbox.notify, ops=(ADD_EDGE, REMOVE_EDGE, UPDATE_NODE), labels=(L.IN_CONTEXT, L.HAS_DEVICE, L.PLATFORM))
        self.repo.subscribe(self.books.count_history, ops=(RELABEL_EDGE,), labels=(L.DEPLOYMENT_HISTORY,))

    # ------------------------------------------------------------------ what tests and harnesses read
    @property
    def reactions(self) -> int:
        return self.books.reactions

    @property
    def audits(self) -> int:
        return self.books.audits

    @property
    def stops(self) -> int:
        return self.infra.stops

    @property
    def history_edges(self) -> int:
        return self.books.history_edges

    def physically_valid(self, graph: str, platform: str) -> bool:
        """Whether the running instance of ``graph`` on ``platform`` can monitor: its
        platform is up and every stream it reads has a readable device (warm-up aside)."""
        return self.facts.physically_valid(graph, platform)

    def _audit(self, after: str = "", skip: frozenset[str] = frozenset(), started: tuple[str, str] | None = None) -> tuple[str, ...]:
        """The named invariants on the live repository (:data:`~desmon.sim.driver.Audit`),
        then, at a quiescent point, ``on_quiescent``."""
        running = tuple(sorted(self.instances))
        booked = audit(self.parts, self.core.view(running=running, stops=self.infra.stops, history=self.books.history_edges), after, skip, started)
        if not after and self.on_quiescent is not None:
            self.on_quiescent(self)
        return booked

    # ------------------------------------------------------------------ run
    def _trace_header(self) -> None:
        """The ``run`` record, the initial loads and the ground-truth slips."""
        trace = self.trace
        trace.emit(
            0.0, "run", scenario=self.scenario.name, deployer=self.deployer_name, seed=self.seed, horizon=self.horizon,
            signals=self.signals_on,
            platforms={p.name: platform_resources(p) for p in self.model.platforms},
            graphs={
                g.name: {**graph_resources(self.query.deployment_information(g.name)), "memory": self.facts.consumes.get(g.name, 0.0)}
                for g in self.model.graphs
            },
            actions=declared_actions(self.model),
        )
        for p in self.model.platforms:
            trace.emit(0.0, "load", platform=p.name, resource="memory", amount=self.facts.load[p.name])
        for p, resource, amount in initial_loads(self.model, self.scenario.initial):
            trace.emit(0.0, "load", platform=p, resource=resource, amount=amount)
        for s in self.slips:
            trace.emit(s.time, "slip", direction=s.direction, kind=s.kind)

    def _ahead_wanted(self) -> bool:
        """Whether this run renders its signals ahead in forked workers (``render_ahead``);
        unasked, only where a graph of the model reads the tactile frames the worker would
        render (a model without one reads none of them) and its detectors read every frame:
        a run read for figures that never see an alarm far from a slip runs its detectors
        near the slips only (:data:`~desmon.sim.metrics.EVERY_ALARM`), and the worker would
        render every second of holding for the few blocks the run takes (docs/design.md,
        "Rendering ahead", gives what it cost)."""
        bank = self.bank
        if bank is None or self.render_ahead is False:
            return False
        if self.render_ahead:
            return True
        return (fork_safe() and self.infra.every_alarm and self._reads_tactile()
                and holding_seconds(bank.signals.tactile_array.episodes, self.horizon) >= AHEAD_MIN_S)

    def _reads_tactile(self) -> bool:
        """Whether some graph's detector reads the tactile stream (its plan: :attr:`Infrastructure.plans`)."""
        return any(plan is not None and TactileStream in plan.streams for plan in self.infra.plans.values())

    def run(self) -> RunResult:
        parts = self.parts
        self._trace_header()
        start_processes(parts, self._audit if self._audited else _unread)
        if self.progress is not None:
            self.env.process(progress(parts, self.progress))
        ahead = self.bank.signals if self._ahead_wanted() and self.bank is not None else None
        if ahead is not None:
            ahead.start_ahead(tactile_flow=flow_ahead)
        try:
            with collector_relaxed(self.collector, collect=False):  # the world built so far stays out of the collector's scans
                self.env.run(until=self.horizon)
        finally:
            if ahead is not None:
                ahead.stop_ahead()
        now = self.horizon
        for inst in list(self.instances.values()):
            self.infra.feed(inst, now)
        parts.exposure.close(now)
        parts.memory.close(now)
        self.books.close_leases(now)
        metrics = robot_metrics(parts)
        self.trace.emit(now, "end", **{k: v for k, v in metrics.items() if k != "latencies"})
        books = self.books
        return RunResult(
            self.scenario, self.world, self.deployer_name, self.seed, self.horizon, self.trace, self.repo, metrics,
            books.decisions, books.errors, books.violations, self.slips, self.infra.alarms,
        )


def _unread(after: str = "", skip: frozenset[str] = frozenset(), started: tuple[str, str] | None = None) -> tuple[str, ...]:
    """The audit of a run nobody reads the violations of: none."""
    return ()


def simulate(scenario: Scenario, deployer: str = "desmon", seed: int = 0, **kw: Any) -> RunResult:
    """Run ``scenario`` in the SimPy world and return the result."""
    return SimWorld(scenario, deployer=deployer, seed=seed, **kw).run()
