"""Deployers with memory are caught, not sampled.

A reaction must be a function of what it reads (docs/deployers.md). The sampled re-runs
of :mod:`desmon.verify.system` compare two runs of one reaction back to back, in the
same deployer: a deployer that counts its calls and changes its answers after a few
hundred, or keeps a cache that changes them, gives the same answer twice in a row and
passes. So a search of a user's deployer (``--deployer path/to/file.py:NAME`` or
``module:NAME``) keeps every reaction it ran (state, event, start outcomes, commands,
failure), and at its end (:func:`check_memory`)

1. :func:`rerun_fresh` runs each once more, *last first*, in a fresh instance of the
   deployer: its module imported again, so its globals, caches and counters start
   afresh, and the reactions come in another order. Other commands, or a failure in one
   run only, are refused as nondeterminism (exit 2) naming both runs; a failure of the
   re-run is named, never lost;
2. the state the deployer's module holds (:func:`deployer_state`: its globals, its
   functions' defaults, attributes and closure cells, its classes' attributes), taken
   when the search's system was built, is compared with what it holds now: a change is
   state kept between reactions, refused (exit 2) naming it, even where it changed no
   answer within the search (a counter that would stop the deployer after more
   reactions than the search ran; a generator's by the variables of its frame).

What it does not see: state kept outside the deployer's module (in another module it
imports, in a file, in an object its globals do not reach) whose effect does not show
in the re-run; a ``functools.lru_cache`` (its repr does not show its contents: over a
function of its arguments it changes no answer); a deployer built in Python (not named
by a spec desmon can import again); the reactions the direct engine's ``--workers``
processes ran (each keeps its own, not sent back).
"""

from __future__ import annotations

import dataclasses

from desmon.errors import NondeterminismError
from desmon.verify.deployers import deployer_state, fresh_deployer, users_spec, worker_state
from desmon.verify.system import TransitionSystem, command_key, crash_of, nondeterminism

__all__ = ["remembers", "rerun_fresh", "check_memory", "check_module_state", "FRESH_NOTE"]

#: what the refusal of a reaction that differed in the fresh instance adds
FRESH_NOTE = (
    "the second run was at the end of the search, in a fresh instance of the deployer (its module imported again) "
    "with the reactions in another order: it keeps state between reactions"
)


def remembers(deployer_name: str) -> bool:
    """Whether a search of this deployer keeps its reactions for :func:`rerun_fresh` (a user's spec)."""
    return users_spec(deployer_name)


def check_memory(system: TransitionSystem) -> None:
    """The end of a search of a user's deployer: :func:`rerun_fresh`, then the state its
    module kept compared with what it was before the search (``system.deployer_state``):
    a global, a function's default, attribute or closure cell, or a class attribute that
    changed is state kept between reactions, refused (:class:`~desmon.errors.NondeterminismError`)."""
    if system.reactions is None:
        return
    rerun_fresh(system)
    check_module_state(system)


def check_module_state(system: TransitionSystem) -> None:
    """The state a user's deployer's module keeps now compared with what it kept just after
    it was imported (``system.deployer_state``; in its worker, that worker's own); a change
    is refused (:class:`~desmon.errors.NondeterminismError`). ``desmon analyze`` asks this
    of the deployer that built its chain, ``desmon verify`` after its fresh re-run."""
    if system.deployer_state is None:
        return
    pair = worker_state(system.core.deployer)  # (its worker's own: as imported there, and now)
    before, after = pair if pair is not None else (system.deployer_state or {}, deployer_state(system.core.deployer))
    for name, was in before.items():
        now = after.get(name)
        if now != was:
            raise NondeterminismError(
                f"deployer {system.deployer_name} keeps state between reactions: its module's {name} changed during the search "
                f"(from {was[:80]} to {(now or 'gone')[:80]}), so its reactions are not a function of what they read; keep no "
                "counters, caches or globals that change (functools.lru_cache over a function of its arguments is fine: docs/deployers.md)"
            )


def rerun_fresh(system: TransitionSystem) -> int:
    """Every reaction ``system``'s search kept, re-run last first in a fresh instance of its
    deployer; raises :class:`~desmon.errors.NondeterminismError` at the first that differs.
    Returns how many it re-ran."""
    kept = system.reactions
    if not kept:
        return 0
    run = dataclasses.replace(system.run_context, checks=None)
    fresh = TransitionSystem(
        system.scenario, fresh_deployer(system.core.deployer), invariants=[i.name for i in system.invariants],
        bounds=system.bounds, run=run,
    )
    for key, event, prefix, commands, instant in reversed(kept):
        _nkey, _outcomes, log, again = fresh.run_one(key, event, prefix)
        same = [command_key(c) for c, _ok in commands] == [command_key(c) for c, _ok in log.commands]
        crashed = (crash_of(instant), crash_of(again))
        if not same or (crashed[0] is None) != (crashed[1] is None):
            was, now = [str(c) for c, _ok in commands], [str(c) for c, _ok in log.commands]
            raise nondeterminism(system.deployer_name, event, was, now, failed=crashed, note=FRESH_NOTE)
    return len(kept)
