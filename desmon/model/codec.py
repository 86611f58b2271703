"""The JSON codec of model values: events and requirements as ``desmon verify --json`` writes them.

:func:`event_to_json` / :func:`event_from_json` and :func:`constraint_to_json` /
:func:`constraint_from_json` turn model values into JSON and back; reading checks every
field as building the value in a scenario does, and names the JSON path of whatever is
wrong on one line (:class:`~desmon.errors.CheckerError`). A requirement kind writes and
reads its own fields (:meth:`~desmon.model.kinds.Constraint.to_json`,
:meth:`~desmon.model.kinds.Requirement.json_args`); the kinds are those of
:func:`~desmon.model.kinds.requirement_kinds`. (Moved from ``desmon.verify.report``,
which re-exports these names.)
"""

from __future__ import annotations

from typing import Any

from desmon.errors import CheckerError, ModelError
from desmon.model.checks import suggest
from desmon.model.events import Event
from desmon.model.kinds import requirement_class, requirement_kinds
from desmon.model.requirements import PREFERENCE_KINDS, Constraint, Preference

__all__ = ["event_to_json", "event_from_json", "constraint_to_json", "constraint_from_json", "json_object"]


# -- events ----------------------------------------------------------------------------------
def event_to_json(e: Event | None) -> dict[str, Any] | None:
    """``e`` as JSON that :func:`event_from_json` rebuilds into an equal event (None for the initial state)."""
    if e is None:
        return None
    return e.to_json(constraint_to_json)  # each kind writes its own keys (Event.to_json)


def constraint_to_json(c: Constraint) -> dict[str, Any]:
    """A requirement as ``{"requirement": KIND, FIELD: value, ...}`` (its dataclass fields by name,
    as its kind writes them), a preference as ``{"preference": KIND, "args": [...], "weight": w}``."""
    return c.to_json()


def event_from_json(data: object, *, where: str = "event") -> Event:
    """The event :func:`event_to_json` wrote. Whatever is wrong in a (hand-edited) ``d`` is a
    one-line :class:`~desmon.errors.CheckerError` naming ``where`` and the field; the
    values pass the same checks as the event built in a scenario."""
    d = json_object(where, data, '{"kind": "action", "action": "grasp"}')
    kind = d.get("kind")
    cls = Event.of_kind(kind)
    if cls is None:
        kinds = [c.kind for c in Event.kinds()]
        raise CheckerError(f"{where}.kind = {kind!r} is not an event kind{suggest(kind, kinds)}: use one of {', '.join(kinds)}")
    required, optional = cls.json_keys()
    _check_keys(where, d, ("kind", *required), optional)
    args = cls.json_args({k: d[k] for k in (*required, *optional) if k in d}, _value_from_json, where)
    return _build(where, cls, args)  # type: ignore[return-value]


def _value_from_json(data: object, *, where: str) -> object:
    """A model value an event's JSON holds: an event (a JSON object with a ``kind``, as a
    :class:`~desmon.model.events.Together` holds two), else a requirement."""
    if isinstance(data, dict) and "kind" in data:
        return event_from_json(data, where=where)
    return constraint_from_json(data, where=where)


def constraint_from_json(data: object, *, where: str = "requirement") -> Constraint:
    """The requirement or preference :func:`constraint_to_json` wrote, checked as when a scenario builds it."""
    d = json_object(where, data, '{"requirement": "capacity", "resource": "memory", "amount": 250}')
    if ("requirement" in d) == ("preference" in d):
        raise CheckerError(
            f"{where} = {d!r} must name one kind, by \"requirement\" (one of {', '.join(requirement_kinds())}) "
            f"or by \"preference\" (one of {', '.join(PREFERENCE_KINDS)})"
        )
    if "preference" in d:
        _check_keys(where, d, ("preference", "args"), ("weight",))
        args = d["args"]
        if not isinstance(args, list):
            raise CheckerError(f"{where}.args = {args!r} is not a list: write a list of names, e.g. [\"memory\"]")
        weight = {"weight": d["weight"]} if "weight" in d else {}
        return _build(where, Preference, {"kind": d["preference"], "args": tuple(args), **weight})  # type: ignore[return-value]
    kind = d["requirement"]
    cls = requirement_class(kind) if isinstance(kind, str) else None
    if cls is None:
        kinds = requirement_kinds()
        raise CheckerError(
            f"{where}.requirement = {kind!r} is not a requirement kind{suggest(kind, kinds)}: use one of {', '.join(kinds)}"
        )
    args = cls.json_args({k: v for k, v in d.items() if k != "requirement"}, where, _item)
    return _build(where, cls, args)  # type: ignore[return-value]


def _item(where: str, cls: type, data: object, example: str) -> object:
    """A nested object of a requirement's JSON (a Selection's option), checked like the rest."""
    return _build(where, cls, json_object(where, data, example))


def json_object(where: str, d: object, example: str) -> dict[str, Any]:
    """``d`` if it is a JSON object (a dict), else a :class:`CheckerError` naming ``where``
    and showing ``example``."""
    if not isinstance(d, dict):
        shown = repr(d)
        shown = shown if len(shown) <= 60 else f"{shown[:57]}..."  # (a whole file's list: one short line)
        raise CheckerError(f"{where} = {shown} is not a JSON object: write e.g. {example}")
    return d


def _check_keys(where: str, d: dict[str, Any], required: tuple[str, ...], optional: tuple[str, ...]) -> None:
    allowed = (*required, *optional)
    for key in d:
        if key not in allowed:
            raise CheckerError(f"{where}: unknown key {key!r}{suggest(key, allowed)}; it holds {', '.join(allowed)}")
    missing = [k for k in required if k not in d]
    if missing:
        raise CheckerError(f"{where}: missing {', '.join(repr(m) for m in missing)}; it holds {', '.join(allowed)}")


def _build(where: str, cls: Any, args: dict[str, Any]) -> object:
    """``cls(**args)``, its one-line ModelError re-raised as a CheckerError naming ``where``."""
    try:
        return cls(**args)
    except ModelError as exc:
        raise CheckerError(f"{where}: {exc}") from None

