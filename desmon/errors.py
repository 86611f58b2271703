"""The desmon exception tree.

Every exception desmon raises on purpose derives from :class:`DesmonError`. Usage
errors also derive from the builtin a caller would naturally catch::

    DesmonError
     ├── ModelError (ValueError)          a malformed platform, graph, spec or rule table
     │    └── DeployerFault               a user's deployer raised, yielded a wrong command or
     │                                    never ended (desmon.deployment.guard)
     ├── ScenarioError (ValueError)       a scenario file that does not load or is inconsistent
     ├── QueryError (LookupError)         a repository query for something that is not there
     ├── SignalError (ValueError)         bad signal-model / detector parameters
     ├── CheckerError                     the checker cannot run as asked
     │    └── NondeterminismError         a replay did not reproduce a stored state
     ├── SimulationError                  the SimPy world reached an impossible state
     └── EstimateError (ValueError)       an estimate asked for what its method cannot give

Messages name the offender and say what would fix it; the CLI prints them as one
line, without a traceback.
"""

from __future__ import annotations

import traceback
from types import TracebackType

__all__ = [
    "DesmonError",
    "ModelError",
    "ScenarioError",
    "QueryError",
    "SignalError",
    "CheckerError",
    "NondeterminismError",
    "ObservationConflict",
    "SimulationError",
    "EstimateError",
    "reading_module",
]


class DesmonError(Exception):
    """Root of every error desmon raises deliberately."""


class ModelError(DesmonError, ValueError):
    """A model (platform, device, perception graph, spec, rule) is malformed."""


class ScenarioError(DesmonError, ValueError):
    """A scenario file cannot be loaded or does not describe a usable scenario."""


class QueryError(DesmonError, LookupError):
    """A repository query names something the repository does not hold."""


class SignalError(DesmonError, ValueError):
    """Signal-model or detector parameters are out of range."""


class CheckerError(DesmonError):
    """The explicit-state checker cannot run as requested."""


class NondeterminismError(CheckerError):
    """Replaying a trace did not reproduce the state the search stored."""


class ObservationConflict(NondeterminismError):
    """The table engine recorded two runs that read the same facts and did otherwise: the
    deployer is nondeterministic, or it learned a fact the engine did not observe
    (``--engine auto`` hands the search to the direct engine, which decides)."""


class TableUnsupported(CheckerError):
    """The table engine cannot run this search (``--engine auto`` falls back to the direct engine)."""


class UnobservedRead(TableUnsupported):
    """A reaction read a platform fact outside the requirement checks: it cannot be memoised.

    ``fact`` names what was read and ``platform`` whose; ``caller`` is the module that
    read it, once the engine that caught the error has found it in the traceback
    (see :meth:`message`)."""

    def __init__(self, message: str = "", *, fact: str = "", platform: str = "") -> None:
        super().__init__(message)
        self.fact, self.platform = fact, platform

    def named(self, caller: str) -> "UnobservedRead":
        """This refusal with the reading module named (what the user is told)."""
        out = UnobservedRead(
            f"{caller} read {self.fact} of platform {self.platform} outside the requirement checks "
            "(desmon.deployment.validity): the table engine cannot memoise this reaction; run with --engine direct",
            fact=self.fact, platform=self.platform,
        )
        return out


def reading_module(tb: TracebackType | None, helpers: tuple[str, ...]) -> str:
    """The module that made a read, from the traceback of its refusal: the innermost frame
    whose module is none of ``helpers`` (modules and packages that read on their caller's
    behalf: ``copy`` is one, ``copycat_deployer`` is not), or "?". Both the table engine and
    an isolated deployer's worker name the reader of an :class:`UnobservedRead` by it."""
    inside = tuple(f"{h}." for h in helpers)
    found = "?"
    for frame, _line in traceback.walk_tb(tb):
        name = str(frame.f_globals.get("__name__", "?"))
        if name not in helpers and not name.startswith(inside):
            found = name
    return found


class SimulationError(DesmonError):
    """The simulation reached a state its own bookkeeping forbids."""


class EstimateError(DesmonError, ValueError):
    """An estimate (``desmon estimate``, :mod:`desmon.stats`) asked for what its method cannot give:
    a confidence outside (0, 1), a precision that is no positive number, a run's value outside the range declared for it."""
