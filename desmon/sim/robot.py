"""The parts of one robot's SimPy world: what its processes share.

:class:`RobotParts` is the context every process of a robot takes
(:mod:`desmon.sim.processes`, the deployer driver :mod:`desmon.sim.driver`, the audit and
metrics of :mod:`desmon.sim.accounting`); :func:`desmon.sim.parts.robot_parts` builds it.
"""

from __future__ import annotations

import random
from dataclasses import dataclass, field

import simpy

from desmon.deployment.core import DeploymentCore
from desmon.model.scenario import Scenario
from desmon.model.system import SystemModel
from desmon.repository.query import RepositoryQuery
from desmon.repository.store import Repository
from desmon.sim.books import Books
from desmon.sim.facts import GroundTruth, PhysicalFacts
from desmon.sim.inbox import Inbox
from desmon.sim.infrastructure import Infrastructure
from desmon.sim.metrics import Exposure, MemoryMeter
from desmon.sim.trace import Trace
from desmon.sim.world import World

__all__ = ["RobotParts"]


@dataclass(frozen=True, eq=False)
class RobotParts:
    """The parts of one robot's world: what its processes share."""

    scenario: Scenario
    model: SystemModel
    world: World
    seed: int
    horizon: float
    signals: bool
    env: simpy.Environment
    repo: Repository
    query: RepositoryQuery
    core: DeploymentCore
    trace: Trace
    facts: PhysicalFacts
    truth: GroundTruth
    exposure: Exposure
    memory: MemoryMeter
    infra: Infrastructure
    books: Books
    inbox: Inbox
    #: exponential timing (World.timing): the delays' random stream, and what the
    #: context monitor has a recognition or notice pending for (("context", ""), and
    #: ("device" or "platform", name) of each component)
    markov: random.Random = field(default_factory=random.Random)
    noticing: set[tuple[str, str]] = field(default_factory=set)
