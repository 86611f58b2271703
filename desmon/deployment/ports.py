"""Ports the deployment core is written against, and the frozen commands it yields.

The deployer never calls the infrastructure itself: a reaction is a generator that
*yields* commands (:class:`Start`, :class:`Stop`, :class:`RaiseError`) and receives
each command's outcome (``True``/``False`` for Start/Stop). The engines drive it:

* :func:`desmon.deployment.core.run_sync` executes commands at once against a
  :class:`ControlPort` (scripted driver, checker, fuzzer);
* the SimPy world executes them with start latency and failures.

Reads go through a :class:`QueryPort`, implemented by the networkx repository and by
the checker's state-backed view; requirement checks through a :class:`ChecksPort`,
whose answers (:class:`Validity`, :class:`Failure`) are defined here with it
(:mod:`desmon.deployment.validity` computes them and re-exports both).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Generator, Protocol, runtime_checkable

from desmon.errors import UnobservedRead
from desmon.model.checks import visible
from desmon.model.kinds import Placing
from desmon.model.platform import Platform
from desmon.model.requirements import DeploymentSpec, Requirement
from desmon.model.system import PlatformState

__all__ = [
    "LAZY_TEXT_TYPES",
    "Start",
    "Stop",
    "RaiseError",
    "Command",
    "Reaction",
    "ErrorRecord",
    "Failure",
    "Validity",
    "DEPLOYMENT_FAILED",
    "NO_ACCEPTABLE_PLATFORMS",
    "DEPLOYMENT_INFORMATION_MISSING",
    "STOPPING_FAILED",
    "ERROR_KINDS",
    "QueryPort",
    "QUERY_METHODS",
    "ChecksPort",
    "PlatformHandle",
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

    def __str__(self) -> str:  # (what a deployer wrote is shown escaped: a terminal control sequence in it does nothing)
        return visible(f"start {self.graph} on {self.platform}")


@dataclass(frozen=True, slots=True)
class Stop:
    """Control.stop(graph, platform); the outcome sent back is True on success."""

    graph: str
    platform: str

    def __str__(self) -> str:
        return visible(f"stop {self.graph} on {self.platform}")


#: the types besides ``str`` a RaiseError's detail may have: desmon's own texts computed when
#: read (a recorded run's explanation registers its type here); a deployer's detail is a str
LAZY_TEXT_TYPES: set[type] = set()


@dataclass(frozen=True, slots=True)
class RaiseError:
    """An Error-port report; the engine stamps it with the time into an :class:`ErrorRecord`.
    ``detail`` is text (a ``str``)."""

    kind: str
    graph: str
    platform: str | None = None
    detail: str = ""

    def __str__(self) -> str:
        where = f" on {self.platform}" if self.platform else ""
        return visible(f"error {self.kind}: {self.graph}{where}" + (f" ({self.detail})" if self.detail else ""))


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


@dataclass(frozen=True, slots=True)
class Failure:
    """One requirement that one platform does not meet, and why."""

    platform: str
    requirement: str
    reason: str

    def __str__(self) -> str:
        return f"{self.platform}: {self.requirement} fails: {self.reason}"


#: the decimals a preference score and a gain are kept to. A score adds weight x term in
#: binary floats (0.1 + 0.2 is 0.30000000000000004), so platforms the user's numbers score
#: alike must still tie (the declaration order decides) and a gain equal to a rebalance's
#: ``min_gain`` must not count as above it; a difference under 5e-13 is no difference
SCORE_DIGITS = 12


@dataclass(frozen=True, slots=True)
class Validity:
    """Result of :func:`~desmon.deployment.validity.check_validity`: acceptable platforms
    (best first) and every failure of every rejected platform.

    With preferences, ``scores`` holds each acceptable platform's score (aligned with
    ``acceptable``) and, when reasons were asked for, ``breakdown`` each one's weighted
    terms per preference; both are empty without preferences.
    """

    acceptable: tuple[str, ...]
    rejected: tuple[tuple[str, tuple[Failure, ...]], ...]
    scores: tuple[float, ...] = ()
    breakdown: tuple[tuple[str, tuple[tuple[str, float], ...]], ...] = ()

    def failures(self, platform: str) -> tuple[Failure, ...]:
        for name, fails in self.rejected:
            if name == platform:
                return fails
        return ()

    def score(self, platform: str) -> float:
        """The preference score of an acceptable ``platform`` (0 without preferences)."""
        if not self.scores:
            return 0.0
        return self.scores[self.acceptable.index(platform)]

    def gain(self, platform: str) -> float:
        """How much the best acceptable platform scores above ``platform`` (0 if it is the best)."""
        if not self.scores or not self.acceptable:
            return 0.0
        return round(self.scores[0] - self.score(platform), SCORE_DIGITS)

    def explain(self) -> str:
        lines = [f"acceptable: {', '.join(self.acceptable) or '(none)'}"]
        for name, terms in self.breakdown:
            parts = " + ".join(f"{what} {value:.3g}" for what, value in terms)
            lines.append(f"score {name}: {sum(v for _w, v in terms):.3g} = {parts}")
        for _name, fails in self.rejected:
            lines.extend(str(f) for f in fails)
        return "\n".join(lines)


class ChecksPort(Protocol):
    """Requirement evaluation (the paper's checkValidity), as the core and every deployer ask it.

    Every answer is the one :func:`desmon.deployment.validity.loop_validity` and
    :func:`~desmon.deployment.validity.platform_failures` compute; implementations differ
    in how: :class:`~desmon.deployment.validity.ScalarChecks` (one platform at a time,
    memoised or not), :class:`~desmon.deployment.placement.ColumnChecks` (numpy columns
    for fleets) and the checker's recording checks (the table engine learns what a
    reaction observed of the platforms). The caller that builds a Query port chooses.
    """

    def validity(self, reqs: tuple[Requirement, ...], states: tuple[Any, ...], graph: "Placing", reasons: bool) -> "Validity":
        """The acceptable platforms among ``states`` for ``graph`` and why the others are not."""

    def platform(self, reqs: tuple[Requirement, ...], state: Any, graph: "Placing", first_only: bool) -> "tuple[Failure, ...]":
        """Every requirement (or the first) that ``state`` fails for ``graph``."""


class PlatformHandle:
    """A platform as the checker's recording Query port hands it out: opaque.

    It carries what a reaction may read freely -- the platform's declaration and what is
    deployed on it (both part of what the table engine keys a reaction on) -- and the
    Checks port that alone can read its run-time facts. Reading ``up``, ``devices`` or
    ``load``, or the handle's text (``repr``, ``str``, a format), raises
    :class:`~desmon.errors.UnobservedRead`: the guard holds by
    construction, since the handle holds no such facts. Handles compare and hash by
    identity (one handle per platform facts and deployments in a recording).
    """

    __slots__ = ("platform", "deployed", "index", "checks")

    def __init__(self, platform: Platform, deployed: tuple, index: int, checks: ChecksPort) -> None:
        self.platform, self.deployed, self.index, self.checks = platform, deployed, index, checks

    @property
    def name(self) -> str:
        return self.platform.name

    def _refuse(self, fact: str) -> UnobservedRead:
        return UnobservedRead(f"read {fact} of platform {self.platform.name} outside the requirement checks", fact=fact, platform=self.platform.name)

    @property
    def up(self) -> bool:
        raise self._refuse("`up`")

    @property
    def devices(self) -> tuple:
        raise self._refuse("`devices`")

    @property
    def load(self) -> tuple:
        raise self._refuse("`load`")

    def load_of(self, resource: str) -> float:
        raise self._refuse("`load`")

    def used_by(self, resource: str, *, excluding: str | None = None) -> list[tuple[str, float]]:
        return PlatformState.used_by(self, resource, excluding=excluding)  # type: ignore[arg-type]

    def with_deployed(self, deployed: tuple) -> "PlatformHandle":
        """The handle of the same platform and facts with other deployments (its checks make it)."""
        return self.checks.derive(self, deployed)  # type: ignore[no-any-return,attr-defined]

    def __eq__(self, other: object) -> bool:
        if self is other:
            return True
        if isinstance(other, (PlatformHandle, PlatformState)):
            raise self._refuse("the facts (comparing states)")
        return NotImplemented

    __hash__ = object.__hash__

    def __repr__(self) -> str:
        # a platform state's text shows its run-time facts: a handle's text would show other
        # words in the same state (a reaction that tests "up=False" in it branches unobserved)
        raise self._refuse("the facts (its repr or str)")


@runtime_checkable
class QueryPort(Protocol):
    """The Query interface of the repository, as Algorithms 1 and 2 use it.

    Besides the named queries it carries three attributes its builder sets: ``checks``,
    the Checks port every requirement question about its platforms goes to (None: the
    default memoised checks); ``specs_version``, a number that changes with every
    run-time requirement change (None: the port rebuilds nothing, so nothing is
    memoised on it); ``validity_memo``, a dict for memoising validity answers on the
    identity of its platform-states tuples (None: every check is performed).
    """

    checks: ChecksPort | None
    specs_version: int | None
    validity_memo: dict | None

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


#: the QueryPort's methods, in declaration order (what a port that offers exactly them lists)
QUERY_METHODS = tuple(name for name, value in vars(QueryPort).items() if callable(value) and not name.startswith("_"))


class ControlPort(Protocol):
    """The infrastructure's Control interface."""

    def start(self, graph: str, platform: str) -> bool: ...

    def stop(self, graph: str, platform: str) -> bool: ...


class ErrorPort(Protocol):
    """The Error interface."""

    def report(self, record: ErrorRecord) -> None: ...

