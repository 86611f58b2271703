"""The kind of slip each built-in action with an object in the hand gives: ``World.slip_kinds``
over the defaults (a module of its own: it needs nothing of the World)."""

from __future__ import annotations

from desmon.errors import ScenarioError
from desmon.model.actions import GRASP, MOVE_BASE, RELEASE
from desmon.model.checks import suggest

__all__ = ["DEFAULT_SLIP_KINDS", "check_slip_kinds"]

#: :attr:`World.slip_kinds` by default: (action, direction, kind) of a random slip
DEFAULT_SLIP_KINDS: tuple[tuple[str, str, str], ...] = (
    (GRASP, "down", "pulled"),
    ("hold", "down", "pulled"),
    (MOVE_BASE, "down", "gravitational"),
    (RELEASE, "up", "pulled"),
    ("rotate_ccw", "down", "pulled"),
    ("rotate_cw", "down", "pulled"),
)


def check_slip_kinds(given: object) -> tuple[tuple[str, str, str], ...]:
    """``World.slip_kinds`` over the defaults: each entry (action, direction, kind) names
    a risky built-in action once, a direction up/down and a kind pulled/gravitational."""
    example = "slip_kinds=(('move_base', 'down', 'pulled'),)"
    if not isinstance(given, (tuple, list)):
        raise ScenarioError(f"world: slip_kinds = {given!r}: give (action, direction, kind) triples, e.g. {example}")
    out = dict((a, (d, k)) for a, d, k in DEFAULT_SLIP_KINDS)
    seen: set[str] = set()
    for entry in given:
        if not (isinstance(entry, (tuple, list)) and len(entry) == 3 and all(isinstance(x, str) for x in entry)):
            raise ScenarioError(f"world: slip_kinds entry {entry!r} is not an (action, direction, kind) triple of names: write e.g. {example}")
        a, d, k = entry
        if a not in out:
            raise ScenarioError(
                f"world: slip_kinds names {a!r}{suggest(a, list(out))}, which is no built-in action with an object in the hand: "
                f"use one of {', '.join(out)} (a model's own action slips like its like=)"
            )
        if a in seen:
            raise ScenarioError(f"world: slip_kinds names {a!r} twice: give each action once")
        seen.add(a)
        if d not in ("up", "down") or k not in ("pulled", "gravitational"):
            raise ScenarioError(
                f"world: slip_kinds entry {tuple(entry)!r}: direction must be 'up' or 'down' and kind 'pulled' or 'gravitational'"
            )
        out[a] = (d, k)
    return tuple((a, d, k) for a, (d, k) in out.items())
