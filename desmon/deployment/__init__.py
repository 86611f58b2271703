"""L3: pure deployment decisions written against ports (Query, Control, Error)."""

from desmon.deployment.core import DeploymentCore, StepLog, run_sync, stamp, standing_after
from desmon.deployment.deployer import DEPLOYERS, DESMON, PAPER, Deployer, ensure_deployed, get_deployer, make_desmon_react
from desmon.deployment.invariants import INVARIANTS, Invariant, SystemView, check_invariants, get_invariants, validly_active, view_of
from desmon.deployment.memo import MemoChecks
from desmon.deployment.monitor import GripperObservation, InsertPort, Stimulus, interpret, observe
from desmon.deployment.ports import (
    DEPLOYMENT_FAILED, DEPLOYMENT_INFORMATION_MISSING, ERROR_KINDS, NO_ACCEPTABLE_PLATFORMS, STOPPING_FAILED,
    ChecksPort, Command, ControlPort, ErrorPort, ErrorRecord, PlatformHandle, QueryPort, RaiseError, Reaction, Start, Stop,
)
from desmon.deployment.run import RunContext
from desmon.deployment.validity import DEFAULT_CHECKS, Failure, ScalarChecks, Validity, acceptable_platforms, check_platform, check_validity, deployment_valid, validity_for

__all__ = [
    "DeploymentCore", "StepLog", "run_sync", "stamp", "standing_after",
    "DEPLOYERS", "DESMON", "PAPER", "Deployer", "ensure_deployed", "get_deployer", "make_desmon_react",
    "INVARIANTS", "Invariant", "SystemView", "check_invariants", "get_invariants", "validly_active", "view_of",
    "GripperObservation", "InsertPort", "Stimulus", "interpret", "observe",
    "DEPLOYMENT_FAILED", "DEPLOYMENT_INFORMATION_MISSING", "ERROR_KINDS", "NO_ACCEPTABLE_PLATFORMS", "STOPPING_FAILED",
    "ChecksPort", "PlatformHandle", "ScalarChecks", "DEFAULT_CHECKS", "Command", "ControlPort", "ErrorPort", "ErrorRecord", "QueryPort", "RaiseError", "Reaction", "Start", "Stop",
    "MemoChecks", "RunContext",
    "Failure", "Validity", "acceptable_platforms", "check_platform", "check_validity", "deployment_valid", "validity_for",
]
