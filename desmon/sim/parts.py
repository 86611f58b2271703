"""One robot's SimPy world as parts, and their assembly.

:class:`RobotParts` (:mod:`desmon.sim.robot`, re-exported here) is the context the
processes share: the run's settings, the SimPy environment, the repository and the
robot's Query port, its deployment core, and the parts themselves --

* the physical facts and ground truth (:mod:`desmon.sim.facts`),
* the Control infrastructure (:mod:`desmon.sim.infrastructure`),
* the books (:mod:`desmon.sim.books`), exposure and memory meters,
* the deployer's inbox (:mod:`desmon.sim.inbox`).

:func:`robot_parts` builds them for one robot; :func:`start_processes` registers the
robot's processes (:mod:`desmon.sim.processes`, the deployer driver
:mod:`desmon.sim.driver`). Both the one-robot :class:`~desmon.sim.engine.SimWorld` and
a fleet's robots (:mod:`desmon.sim.fleet`) are assembled this way: they differ in the
environment and repository (own or shared), the Query port, the Control rules, the
trace and the audit.
"""

from __future__ import annotations

import random
from typing import Any, Callable

import simpy

from desmon.deployment.control import ControlRules
from desmon.deployment.core import DeploymentCore
from desmon.deployment.guard import Guard
from desmon.deployment.run import RunContext
from desmon.deployment.exposure import Needs, cause
from desmon.model.scenario import Scenario
from desmon.repository.facts import RepositoryInsert
from desmon.repository.query import RepositoryQuery
from desmon.repository.store import Repository
from desmon.sim import processes as P
from desmon.sim.books import Books
from desmon.sim.driver import Audit, deployer
from desmon.sim.facts import GroundTruth, PhysicalFacts
from desmon.sim.inbox import Inbox
from desmon.sim.infrastructure import Infrastructure
from desmon.sim.metrics import Exposure, MemoryMeter
from desmon.sim.robot import RobotParts
from desmon.sim.trace import Trace
from desmon.sim.world import World

__all__ = ["RobotParts", "robot_parts", "start_processes"]


def robot_parts(
    scenario: Scenario, world: World, *, env: simpy.Environment, repo: Repository, query: RepositoryQuery, deployer: Any,
    seed: int, horizon: float, signals: bool, trace: Trace, rules: Callable[[ControlRules], Any] | None = None,
    keep_decisions: bool = True, guard: Guard | None = None, run: RunContext | None = None, every_alarm: bool = True,
) -> RobotParts:
    """The parts of ``scenario``'s robot on ``env`` and ``repo`` (read through ``query``).

    ``rules`` wraps the Control rules (a fleet's edge servers add their admission
    control); ``keep_decisions`` False: decisions go to the trace only; ``every_alarm``
    False: the detectors run only where an alarm could fall in a slip's detection window
    (:class:`~desmon.sim.infrastructure.Infrastructure`); ``guard``: the
    run's guard around the deployer (:mod:`desmon.deployment.guard`), or ``run``: the
    whole run context (:mod:`desmon.deployment.run`)."""
    model = scenario.model
    core = DeploymentCore(model, query, RepositoryInsert(repo, model.robot), deployer, guard, run)
    facts = PhysicalFacts(model)
    control = ControlRules(model, query.deployment_information, query.checks)
    truth = GroundTruth(world, model, horizon, seed, signals)

    def emit_exposure(t: float, state: str, context: str) -> None:
        trace.emit(t, "exposure", state=state, context=context)

    def cause_of(need: Needs) -> str | None:
        return cause(need, lambda g: facts.member_state(g, env.now))

    exposure = Exposure(facts.valid_from, emit_exposure, facts.valid_times, cause_of)
    memory = MemoryMeter({p.name: p.capacity_or_unbounded("memory") for p in model.platforms})
    infra = Infrastructure(
        env, world, repo, trace, facts, truth, rules(control) if rules is not None else control, exposure, memory,
        seed=seed, signals=signals, every_alarm=every_alarm,
    )
    return RobotParts(
        scenario, model, world, seed, horizon, signals, env, repo, query, core, trace, facts, truth, exposure, memory, infra,
        Books(trace, keep_decisions), Inbox(repo), random.Random(f"{seed}:timing"),
    )


def start_processes(parts: RobotParts, audit: Audit) -> None:
    """Register the robot, the deployer (auditing with ``audit``) and the world's fault,
    load and change processes."""
    env = parts.env
    world = parts.world
    env.process(P.robot(parts))
    env.process(deployer(parts, audit))
    if world.faults:
        env.process(P.scripted_faults(parts))
    for m in world.stochastic_faults:
        env.process(P.stochastic_faults(parts, m.component, m.mttf, m.mttr))
    if world.loads:
        env.process(P.scripted_loads(parts))
    for i in range(len(world.load_walks)):
        env.process(P.load_walk(parts, i))
    for i in range(len(world.load_steps)):
        env.process(P.load_steps(parts, i))
    if world.changes:
        env.process(P.scripted_changes(parts))
    if world.random_changes is not None:
        env.process(P.random_changes(parts))
