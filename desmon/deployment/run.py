"""One run's context: what a command or a library call hands to every engine it runs.

A :class:`RunContext` carries

* ``guard``: the :class:`~desmon.deployment.guard.Guard` around the deployer -- its
  limits (``--max-commands``), its deadline (``--max-reaction-seconds``) and, while a
  search runs, the search's budget (time, memory, Ctrl-C), which
  :func:`desmon.verify.checker.check` installs on it for the search's length
  (:meth:`Guard.watching <desmon.deployment.guard.Guard.watching>`);
* ``checks``: the run's Checks port with its memos, a
  :class:`~desmon.deployment.memo.MemoChecks` (None: each engine wraps the kind of
  checks it needs -- the checker the scalar checks with every answer memoised, a
  simulated robot the per-platform memo -- and records it on its own context);
* ``outputs``: the files the command writes (what the command line planned; a
  library call plans none).

The context is frozen: a run's settings do not change while it runs, and two runs in
one process (two checks with different limits, a check inside a simulation) each hold
their own. What changes during a run lives on the objects it names (the guard's watch,
the memos), which no other run holds.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Callable

from desmon.deployment.guard import Guard
from desmon.deployment.memo import MemoChecks
from desmon.deployment.ports import ChecksPort

__all__ = ["RunContext", "run_context"]


@dataclass(frozen=True)
class RunContext:
    """A run's guard, Checks port and planned outputs (see the module doc)."""

    guard: Guard = field(default_factory=Guard)
    checks: MemoChecks | None = None
    outputs: tuple[str, ...] = ()

    def with_checks(self, make: Callable[[], ChecksPort], *, answers: bool = True) -> "RunContext":
        """This context with its ``checks`` set: kept if it has some, else ``make()``
        wrapped in a new :class:`~desmon.deployment.memo.MemoChecks` (``answers``: keep
        whole answers, as the checker does; False: the inner checks memoise their own way)."""
        if self.checks is not None:
            return self
        return dataclasses.replace(self, checks=MemoChecks(make(), answers=answers))


def run_context(run: RunContext | None, guard: Guard | None) -> RunContext:
    """The context of a call given ``run`` and/or (the older way) ``guard``: ``run`` if
    given (a ``guard`` as well must be its own), else a new context around ``guard``."""
    if run is None:
        return RunContext(guard=guard if guard is not None else Guard())
    if guard is not None and guard is not run.guard:
        from desmon.errors import ModelError

        raise ModelError("a run context and another guard were both given: pass the guard inside the context, RunContext(guard=...)")
    return run
