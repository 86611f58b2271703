"""What "unmonitored exposure" means: the one definition every engine counts by.

*Risky time* is time with an object in the hand: the true action is one of the model's
risky actions (``SystemModel.risky_actions``: the built-ins ``grasp``, ``hold``,
``move_base``, ``release``, ``rotate_*`` and every action declared ``risky=True``).

A moment of risky time is **unmonitored** unless, for every slot the selector's rule for
the true action wants (a slot is a set of alternative detectors), some member is
*watching*: deployed, started (its start latency over), warmed up, on a platform that is
up, with a readable device for every input, and able to detect a slip in this action
(its inputs have a signal model, or the user gave its detection rate). A risky action
that no rule covers is unmonitored all the time: nothing is asked to watch it.

An action the scenario explicitly excludes (``robot.action("hold", watched=False)``)
is risky time that is never unmonitored: its seconds are reported as *excluded*
beside every figure, and the unmonitored share is of the risky time not excluded.

Each unmonitored moment has one **cause**, so that a report can say where its figure
comes from. The first slot (in the rule's order) without a watching member decides; of
its members the one closest to watching names the cause:

==================  ===========================================================
``no_rule``         the action is risky and no selector rule covers it
``starting``        a member is deployed but starting or warming up
``input_lost``      a member is deployed but its platform is down or an input is
                    unreadable
``cannot_detect``   a member runs but cannot detect a slip here (no signal model
                    for an input, or a detection rate of zero in this action)
``not_deployed``    no member is deployed (no acceptable platform, the deployer
                    has not reacted yet, or it chose not to)
==================  ===========================================================

The simulation (:mod:`desmon.sim.metrics`), ``desmon analyze``
(:mod:`desmon.analyze.chain`), the fleet, the sweeps' columns and the trace all call
:func:`needs` and :func:`cause`; none re-states the rule.
"""

from __future__ import annotations

import math

from dataclasses import dataclass
from typing import Callable, Final, Iterable

__all__ = [
    "CAUSES", "CAUSE_TEXT", "MEMBER_STATES", "WATCHING", "Needs", "needs", "needs_table", "cause", "best_state", "uncovered_actions",
    "no_rule_seconds", "no_rule_warnings", "fleet_no_rule_warnings",
]

#: the causes of an unmonitored moment, in report order
CAUSES: Final = ("no_rule", "not_deployed", "starting", "input_lost", "cannot_detect")
#: what each cause means, as reports print it
CAUSE_TEXT: Final = {
    "no_rule": "risky action no rule covers",
    "not_deployed": "no detector deployed",
    "starting": "detector starting or warming up",
    "input_lost": "platform down or input lost",
    "cannot_detect": "detector cannot detect here",
}
#: a slot member's state, best first (``watching`` covers the slot; the others are causes)
WATCHING: Final = "watching"
MEMBER_STATES: Final = (WATCHING, "starting", "input_lost", "cannot_detect", "not_deployed")
_RANK: Final = {s: i for i, s in enumerate(MEMBER_STATES)}


@dataclass(frozen=True, slots=True)
class Needs:
    """What the definition asks of one true action.

    ``counted``: the action is risky and not excluded (its time is risky time that can
    be unmonitored); ``excluded``: risky, but the scenario declared it ``watched=False``;
    ``slots``: the selector's slots for it (empty with ``counted``: no rule covers it).
    """

    action: str
    counted: bool
    excluded: bool
    slots: tuple[frozenset[str], ...]

    @property
    def risky(self) -> bool:
        return self.counted or self.excluded

    @property
    def no_rule(self) -> bool:
        return self.counted and not self.slots


def needs(model: object, action: str) -> Needs:
    """What ``model`` (a ``SystemModel``) asks of ``action``."""
    risky = action in model.risky_actions  # type: ignore[attr-defined]
    excluded = risky and action in model.unwatched_actions  # type: ignore[attr-defined]
    slots: tuple[frozenset[str], ...] = ()
    if risky and not excluded:
        slots = tuple(frozenset((s,) if isinstance(s, str) else s) for s in model.rules.slots_for(action))  # type: ignore[attr-defined]
    return Needs(action, risky and not excluded, excluded, slots)


def needs_table(model: object) -> dict[str, Needs]:
    """:func:`needs` of every action of ``model``: an engine makes it once per run."""
    return {a: needs(model, a) for a in model.actions}  # type: ignore[attr-defined]


def cause(need: Needs, member: Callable[[str], str]) -> str | None:
    """The cause of the moment (one of :data:`CAUSES`), or None when it is not
    unmonitored; ``member(graph)`` is the graph's state, one of :data:`MEMBER_STATES`
    (the best over its instances)."""
    if not need.counted:
        return None
    if not need.slots:
        return "no_rule"
    for slot in need.slots:
        best = min((_RANK[member(g)] for g in sorted(slot)), default=_RANK["not_deployed"])
        if best:
            return MEMBER_STATES[best]
    return None


def best_state(states: Iterable[str]) -> str:
    """The best of several instances' states (``not_deployed`` if there are none)."""
    return min(states, key=_RANK.__getitem__, default="not_deployed")


def uncovered_actions(model: object, actions: Iterable[str]) -> tuple[str, ...]:
    """The risky, not excluded actions among ``actions`` that no selector rule covers, in
    first-seen order (the scenario warnings name them)."""
    out: list[str] = []
    for a in actions:
        if a not in out and needs(model, a).no_rule:
            out.append(a)
    return tuple(out)


def no_rule_seconds(model: object, steps: Iterable[tuple[str, float]], horizon: float, repeat: bool) -> dict[str, float]:
    """Seconds of each risky, not excluded action that no rule covers, over a task of
    ``steps`` ((action, duration) pairs) played from 0 to ``horizon`` (repeating if
    ``repeat``), with every step its given duration."""
    steps = tuple(steps)
    uncovered = {action for action, _d in steps if needs(model, action).no_rule}
    cycle = sum(duration for _a, duration in steps)
    # the whole cycles in closed form (a horizon of a billion cycles takes no longer), then the rest
    full = math.floor(horizon / cycle) if repeat and cycle > 0 else 0
    out: dict[str, float] = {}
    for action, duration in steps:
        if action in uncovered and full:
            out[action] = out.get(action, 0.0) + full * duration
    t = full * cycle
    for action, duration in steps:
        if t >= horizon:
            break
        if action in uncovered:
            out[action] = out.get(action, 0.0) + min(duration, horizon - t)
        t += duration
    return out


def no_rule_warnings(model: object, steps: Iterable[tuple[str, float]], horizon: float, repeat: bool, *, drawn: bool = False) -> list[str]:
    """One line per risky action that no selector rule covers: what it adds to the
    unmonitored exposure, and the two ways out (``run``, ``verify`` and ``analyze``
    print them before their results). The seconds are the task's with its steps as
    written; ``drawn``: the figure they go with draws the steps' lengths (exponential
    timing, the chain), and the line says that its own seconds differ."""
    lines = []
    for action, seconds in no_rule_seconds(model, steps, horizon, repeat).items():
        at = " at the steps' written lengths (the figures draw the lengths, so theirs differ)" if drawn else ""
        lines.append(
            f"warning: risky action {action!r} has no selector rule, so nothing watches it: its {seconds:,.4g} s of the "
            f"{horizon:,.0f} s horizon{at} count as unmonitored (add a rule for {action!r}, or exclude it on purpose with "
            f"robot.action({action!r}, watched=False))"
        )
    return lines


def fleet_no_rule_warnings(robots: Iterable[tuple[object, Iterable[tuple[str, float]], bool]], horizon: float) -> list[str]:
    """:func:`no_rule_warnings` for a fleet: one line per risky action that no rule covers
    on some robot (``robots``: each one's model, task steps and ``repeat``), with how
    many robots and the mean seconds per robot it adds."""
    seconds: dict[str, list[float]] = {}
    n = 0
    for model, steps, repeat in robots:
        n += 1
        for action, v in no_rule_seconds(model, steps, horizon, repeat).items():
            seconds.setdefault(action, []).append(v)
    return [
        f"warning: risky action {action!r} has no selector rule on {f'{len(vs)} of the {n} robots' if n > 1 else 'the one robot'}, "
        f"so nothing watches it there: {_per_robot(vs)} of the {horizon:,.0f} s horizon count as unmonitored (add a rule for "
        f"{action!r}, or exclude it on purpose with robot.action({action!r}, watched=False))"
        for action, vs in seconds.items()
    ]


def _per_robot(seconds: list[float]) -> str:
    """The no-rule seconds of the robots a warning names: one figure where they agree, else the mean and the range."""
    low, high, mean = min(seconds), max(seconds), sum(seconds) / len(seconds)
    if f"{low:,.4g}" == f"{high:,.4g}":
        return f"{mean:,.4g} s per such robot"
    return f"{mean:,.4g} s per such robot on average ({low:,.4g} to {high:,.4g} s)"
