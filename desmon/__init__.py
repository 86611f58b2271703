"""desmon: adaptive deployment of safety monitors, simulated, exhaustively checked and fuzzed.

The open, runnable version of Hochgeschwender's SAFECOMP 2019 case study: a Care-O-bot 3
carrying a hot coffee mug, three in-hand slip detectors as safety monitors, and the
deployer (Algorithms 1 and 2) that keeps them on platforms meeting their requirements.
"""

from desmon.api import check, simulate
from desmon.deployment import DEPLOYERS, INVARIANTS, DeploymentCore, check_validity
from desmon.errors import (
    CheckerError,
    DesmonError,
    ModelError,
    NondeterminismError,
    QueryError,
    ScenarioError,
    SignalError,
    SimulationError,
)
from desmon.loader import load_scenario
from desmon.model import RobotBuilder, RuleTable, SystemModel
from desmon.model.scenario import Scenario, TimedEvent
from desmon.repository import Repository, RepositoryQuery

__version__ = "0.1.0"

__all__ = [
    "__version__",
    "check",
    "simulate",
    "DEPLOYERS",
    "INVARIANTS",
    "DeploymentCore",
    "check_validity",
    "CheckerError",
    "DesmonError",
    "ModelError",
    "NondeterminismError",
    "QueryError",
    "ScenarioError",
    "SignalError",
    "SimulationError",
    "load_scenario",
    "RobotBuilder",
    "RuleTable",
    "SystemModel",
    "Scenario",
    "TimedEvent",
    "Repository",
    "RepositoryQuery",
]
