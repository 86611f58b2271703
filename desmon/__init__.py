"""desmon: adaptive deployment of safety monitors, simulated, exhaustively checked and fuzzed.

The open, runnable version of Hochgeschwender's SAFECOMP 2019 case study: a Care-O-bot 3
carrying a hot coffee mug, three in-hand slip detectors as safety monitors, and the
deployer (Algorithms 1 and 2) that keeps them on platforms meeting their requirements.

Each name below is imported when first used (``desmon.X`` or ``from desmon import X``),
so ``import desmon`` -- and the command line's ``desmon --help`` -- loads neither
networkx nor numpy.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from desmon.api import check, simulate
    from desmon.deployment import DEPLOYERS, INVARIANTS, DeploymentCore, check_validity
    from desmon.errors import (
        CheckerError,
        DesmonError,
        EstimateError,
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

#: the public names and the module each is imported from when first used
_EXPORTS = {
    "check": "desmon.api",
    "simulate": "desmon.api",
    "DEPLOYERS": "desmon.deployment",
    "INVARIANTS": "desmon.deployment",
    "DeploymentCore": "desmon.deployment",
    "check_validity": "desmon.deployment",
    "CheckerError": "desmon.errors",
    "DesmonError": "desmon.errors",
    "EstimateError": "desmon.errors",
    "ModelError": "desmon.errors",
    "NondeterminismError": "desmon.errors",
    "QueryError": "desmon.errors",
    "ScenarioError": "desmon.errors",
    "SignalError": "desmon.errors",
    "SimulationError": "desmon.errors",
    "load_scenario": "desmon.loader",
    "RobotBuilder": "desmon.model",
    "RuleTable": "desmon.model",
    "SystemModel": "desmon.model",
    "Scenario": "desmon.model.scenario",
    "TimedEvent": "desmon.model.scenario",
    "Repository": "desmon.repository",
    "RepositoryQuery": "desmon.repository",
}

__all__ = ["__version__", *_EXPORTS]


def __getattr__(name: str) -> Any:
    """The public name ``name``, imported from its module on first use (PEP 562)."""
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'desmon' has no attribute {name!r}")
    return getattr(importlib.import_module(module), name)


def __dir__() -> list[str]:
    return sorted({*globals(), *_EXPORTS})
