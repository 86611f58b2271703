"""Ports the deployment core is written against, and the frozen commands it yields.

The deployer never calls the infrastructure itself: a reaction is a generator that
*yields* commands (:class:`Start`, :class:`Stop`, :class:`RaiseError`) and receives
each command's outcome (``True``/``False`` for Start/Stop). The engines drive it:

* :func:`desmon.deployment.core.run_sync` executes commands at once against a
  :class:`ControlPort` (scripted driver, checker, fuzzer);
* the SimPy world executes them with start latency and failures.

Reads go through a :class:`QueryPort`, implemented by the networkx repository and by
the checker's state-backed view.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Generator, Protocol, runtime_checkable

from desmon.model.requirements import DeploymentSpec, Requirement
from desmon.model.system import PlatformState

__all__ = [
    "Start",
    "Stop",
    "RaiseError",
    "Command",
    "Reaction",
    "ErrorRecord",
    "DEPLOYMENT_FAILED",
    "NO_ACCEPTABLE_PLATFORMS",
    "DEPLOYMENT_INFORMATION_MISSING",
    "STOPPING_FAILED",
    "ERROR_KINDS",
    "QueryPort",
    "ControlPort",
    "ErrorPort",
    "relay",
]

DEPLOYMENT_FAILED = "deployment_failed"
NO_ACCEPTABLE_PLATFORMS = "no_acceptable_platforms"
DEPLOYMENT_INFORMATION_MISSING = "deployment_information_missing"
STOPPING_FAILED = "stopping_failed"
ERROR_KINDS = (DEPLOYMENT_FAILED, NO_ACCEPTABLE_PLATFORMS, DEPLOYMENT_INFORMATION_MISSING, STOPPING_FAILED)


@dataclass(frozen=True, slots=True)
class Start:
    """Control.start(graph, platform); the outcome sent back is True on success."""

    graph: str
    platform: str

    def __str__(self) -> str:
        return f"start {self.graph} on {self.platform}"


@dataclass(frozen=True, slots=True)
class Stop:
    """Control.stop(graph, platform); the outcome sent back is True on success."""

    graph: str
    platform: str

    def __str__(self) -> str:
        return f"stop {self.graph} on {self.platform}"


@dataclass(frozen=True, slots=True)
class RaiseError:
    """An Error-port report; the engine stamps it with the time into an :class:`ErrorRecord`."""

    kind: str
    graph: str
    platform: str | None = None
    detail: str = ""

    def __str__(self) -> str:
        where = f" on {self.platform}" if self.platform else ""
        return f"error {self.kind}: {self.graph}{where}" + (f" ({self.detail})" if self.detail else "")


Command = Start | Stop | RaiseError
#: A reaction: yields commands, receives each Start/Stop outcome (None for RaiseError).
Reaction = Generator[Command, "bool | None", None]


@dataclass(frozen=True, slots=True)
class ErrorRecord:
    """An error as the Error interface records it: kind, graph, platform and time."""

    kind: str
    graph: str
    platform: str | None
    time: float
    detail: str = ""

    def to_json(self) -> dict[str, object]:
        return {"kind": self.kind, "graph": self.graph, "platform": self.platform, "time": self.time, "detail": self.detail}


def relay(
    reaction: Reaction,
    before: "Callable[[Command], None] | None" = None,
    after: "Callable[[Command, bool | None], None] | None" = None,
) -> Reaction:
    """``reaction`` passed through command by command, for whoever watches it: ``before(cmd)``
    as each command is yielded, ``after(cmd, outcome)`` once its outcome came back."""
    outcome: bool | None = None
    while True:
        try:
            cmd = reaction.send(outcome)
        except StopIteration:
            return
        if before is not None:
            before(cmd)
        outcome = yield cmd
        if after is not None:
            after(cmd, outcome)


@runtime_checkable
class QueryPort(Protocol):
    """The Query interface of the repository, as Algorithms 1 and 2 use it."""

    def deployment_information(self, graph: str) -> DeploymentSpec | None:
        """d_i: the deployment node resolving ``graph``, or None (Alg. 1 line 3)."""

    def fixed_platform(self, spec: DeploymentSpec) -> str | None:
        """The EXECUTABLE_ON platform of ``spec`` or None (hasFixedDeployment / getFixedPlatform)."""

    def constraints(self, spec: DeploymentSpec) -> tuple[Requirement, ...]:
        """C: the requirements of ``spec`` (getConstraints)."""

    def platform_states(self) -> tuple[PlatformState, ...]:
        """Every platform's run-time facts in declaration order (what checkValidity reads)."""

    def deployed_on(self, graph: str) -> tuple[str, ...]:
        """Platforms ``graph`` is active on (isDeployed(g, P) is ``any(p in P ...)``)."""

    def active_deployments(self, platform: str) -> tuple[str, ...]:
        """D: deployments active on ``platform`` (getActiveDeployments), sorted."""

    def deployments(self) -> tuple[tuple[str, str], ...]:
        """Every active (graph, platform) pair, sorted (all DEPLOYED_ON edges)."""

    def perception_graph(self, deployment: str) -> str:
        """g_i: the perception graph a deployment resolves (getPerceptionGraph)."""

    def context(self) -> str | None:
        """The robot's current action context."""


class ControlPort(Protocol):
    """The infrastructure's Control interface."""

    def start(self, graph: str, platform: str) -> bool: ...

    def stop(self, graph: str, platform: str) -> bool: ...


class ErrorPort(Protocol):
    """The Error interface."""

    def report(self, record: ErrorRecord) -> None: ...

