"""The checker's bounds: which environment events a scenario lets the checker choose.

A scenario passes ``checker=Bounds(...)``; the model layer stays untouched (the
``Scenario.checker`` field is typed ``Any``). :meth:`Bounds.validate` rejects bounds
that name unknown actions, devices or platforms with one clear :class:`CheckerError`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping

from desmon.errors import CheckerError
from desmon.model.actions import ACTIONS
from desmon.model.events import ActionChange, LoadChange
from desmon.model.scenario import Scenario

__all__ = ["Bounds", "levels", "bounds_of", "INSTANT_INVARIANTS"]

#: Invariants that are physical facts at every instant, not only when quiescent; the
#: checker evaluates them after every Start/Stop inside a reaction as well.
INSTANT_INVARIANTS = ("single-instance", "no-overcommit", "fixed")


def levels(low: float, high: float, step: float) -> tuple[float, ...]:
    """``levels(0, 300, 100) == (0, 100, 200, 300)``: load levels for :class:`Bounds`."""
    if step <= 0 or high < low:
        raise CheckerError(f"load levels {low}..{high} step {step}: need low <= high and a positive step")
    out, x = [], low
    while x <= high + 1e-9:
        out.append(x)
        x += step
    return tuple(out)


@dataclass(frozen=True)
class Bounds:
    """What the environment may do, per transition and in total.

    ``actions``
        contexts the robot may switch among, any to any (unless ``task`` is given);
    ``task``
        a task automaton ``{action: (next actions...)}`` replacing any-to-any;
    ``initial_action``
        the context of the initial state (default: the first ActionChange of the
        scenario's timeline, else none);
    ``devices`` / ``platforms``
        devices that may fail (and be repaired), platforms that may go down (and up);
    ``loads``
        ``{platform: levels}`` background load of ``load_resource`` moving one level
        per event (e.g. ``levels(0, 300, 100)``);
    ``start_failures``
        how many Control.start calls may fail within one transition;
    ``max_failures``
        bound on simultaneous failures (failed devices + platforms down);
    ``interchangeable``
        groups of platforms symmetry reduction may permute (``--symmetry``);
    ``instantaneous``
        invariants also checked after every command inside a reaction.
    """

    actions: tuple[str, ...] = ()
    task: Mapping[str, tuple[str, ...]] | None = None
    initial_action: str | None = None
    devices: tuple[str, ...] = ()
    repair: bool = True
    platforms: tuple[str, ...] = ()
    loads: Mapping[str, tuple[float, ...]] = field(default_factory=dict)
    load_resource: str = "memory"
    start_failures: int = 0
    max_failures: int | None = None
    interchangeable: tuple[tuple[str, ...], ...] = ()
    instantaneous: tuple[str, ...] = INSTANT_INVARIANTS

    def action_moves(self, current: str | None) -> tuple[str, ...]:
        if self.task is not None:
            return tuple(self.task.get(current or "", ())) if current is not None else tuple(self.task)
        return tuple(a for a in self.actions if a != current)

    def start_action(self, scenario: Scenario) -> str | None:
        if self.initial_action is not None:
            return self.initial_action
        for te in scenario.timeline:
            if isinstance(te.event, ActionChange):
                return te.event.action
        return None

    def validate(self, scenario: Scenario) -> None:
        m = scenario.model
        where = f"scenario {scenario.name!r} checker bounds"
        acts = set(self.actions) | ({self.initial_action} if self.initial_action else set())
        if self.task is not None:
            for a, nxt in self.task.items():
                acts.add(a)
                acts.update(nxt)
        for a in acts:
            if a not in ACTIONS:
                raise CheckerError(f"{where}: unknown action {a!r}; use one of {', '.join(ACTIONS)}")
        devices = {d.name for d in m.devices}
        for d in self.devices:
            if d not in devices:
                raise CheckerError(f"{where}: unknown device {d!r} (known: {', '.join(sorted(devices))})")
        platforms = [p.name for p in m.platforms]
        for p in (*self.platforms, *self.loads, *(q for grp in self.interchangeable for q in grp)):
            if p not in platforms:
                raise CheckerError(f"{where}: unknown platform {p!r} (known: {', '.join(platforms)})")
        initial_load = {ev.platform: ev.amount for ev in scenario.initial if isinstance(ev, LoadChange) and ev.resource == self.load_resource}
        for p, lv in self.loads.items():
            if isinstance(lv, (str, bytes)) or not isinstance(lv, (tuple, list)) or not all(
                isinstance(x, (int, float)) and not isinstance(x, bool) and x >= 0 for x in lv
            ):
                raise CheckerError(
                    f"{where}: load levels of {p!r} must be a sequence of non-negative numbers, got {lv!r}; "
                    "write e.g. levels(0, 300, 100)"
                )
            if not lv:
                raise CheckerError(f"{where}: platform {p!r} has no load levels")
            if len(set(lv)) != len(lv):
                raise CheckerError(f"{where}: load levels of {p!r} repeat a level ({list(lv)}); list each level once, e.g. levels(0, 300, 100)")
            if initial_load.get(p, 0) not in lv:
                raise CheckerError(
                    f"{where}: initial {self.load_resource} load {initial_load.get(p, 0):g} of {p!r} is not one of its levels {list(lv)}"
                )
        if self.start_failures < 0 or (self.max_failures is not None and self.max_failures < 0):
            raise CheckerError(f"{where}: start_failures and max_failures must be >= 0")
        from desmon.deployment.invariants import INVARIANTS

        for n in self.instantaneous:
            if n not in INVARIANTS:
                raise CheckerError(f"{where}: unknown invariant {n!r} in instantaneous")


def bounds_of(scenario: Scenario) -> Bounds:
    """The scenario's bounds (a :class:`Bounds` or a dict of its fields), validated."""
    b = scenario.checker
    if b is None:
        raise CheckerError(
            f"scenario {scenario.name!r} declares no checker bounds: pass checker=Bounds(actions=..., devices=...) to its Scenario"
        )
    if isinstance(b, Mapping):
        try:
            b = Bounds(**dict(b))
        except TypeError as exc:
            import dataclasses

            fields = ", ".join(f.name for f in dataclasses.fields(Bounds))
            raise CheckerError(f"scenario {scenario.name!r}: bad checker bounds: {exc}; the fields are {fields}") from None
    if not isinstance(b, Bounds):
        raise CheckerError(f"scenario {scenario.name!r}: checker must be a desmon.verify.Bounds, got {type(b).__name__}")
    b.validate(scenario)
    return b
