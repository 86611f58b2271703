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
from desmon.model.events import (
    ActionChange, DeviceFail, DeviceRepair, Event, LoadChange, PlatformDown, PlatformJoin, PlatformLeave, PlatformUp, RequirementChange,
    event_kind,
)
from desmon.model.kinds import requirement_class, requirement_kinds
from desmon.model.requirements import PREFERENCE_KINDS, Constraint, Preference

__all__ = ["event_to_json", "event_from_json", "constraint_to_json", "constraint_from_json"]


# -- events ----------------------------------------------------------------------------------
#: ``kind`` of an event in the JSON -> the keys it holds besides ``kind`` (required ones first)
_EVENT_KEYS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "action": (("action",), ()),
    "device_fail": (("device",), ()),
    "device_repair": (("device",), ()),
    "platform_down": (("platform",), ()),
    "platform_up": (("platform",), ()),
    "platform_join": (("platform",), ()),
    "platform_leave": (("platform",), ()),
    "load": (("platform", "amount"), ("resource",)),
    "requirements": (("graph",), ("label", "add", "remove")),
}
_SIMPLE_EVENTS: dict[str, Any] = {
    "action": ActionChange, "device_fail": DeviceFail, "device_repair": DeviceRepair, "platform_down": PlatformDown,
    "platform_up": PlatformUp, "platform_join": PlatformJoin, "platform_leave": PlatformLeave,
}
_OLD_FORMAT = (
    "written by an older desmon, which kept a requirement change by its description only: "
    "re-run desmon verify --json to write it in full"
)


def event_to_json(e: Event | None) -> dict[str, Any] | None:
    """``e`` as JSON that :func:`event_from_json` rebuilds into an equal event (None for the initial state)."""
    if e is None:
        return None
    kind = event_kind(e)
    if isinstance(e, LoadChange):
        return {"kind": kind, "platform": e.platform, "amount": e.amount, "resource": e.resource}
    if isinstance(e, RequirementChange):
        return {
            "kind": kind, "graph": e.graph, "label": e.label,
            "add": [constraint_to_json(r) for r in e.add], "remove": [constraint_to_json(r) for r in e.remove],
        }
    (field,) = _EVENT_KEYS[kind][0]
    return {"kind": kind, field: getattr(e, field)}


def constraint_to_json(c: Constraint) -> dict[str, Any]:
    """A requirement as ``{"requirement": KIND, FIELD: value, ...}`` (its dataclass fields by name,
    as its kind writes them), a preference as ``{"preference": KIND, "args": [...], "weight": w}``."""
    return c.to_json()


def event_from_json(data: object, *, where: str = "event") -> Event:
    """The event :func:`event_to_json` wrote. Whatever is wrong in a (hand-edited) ``d`` is a
    one-line :class:`~desmon.errors.CheckerError` naming ``where`` and the field; the
    values pass the same checks as the event built in a scenario."""
    d = _mapping(where, data, '{"kind": "action", "action": "grasp"}')
    kind = d.get("kind")
    if not isinstance(kind, str) or kind not in _EVENT_KEYS:
        raise CheckerError(
            f"{where}.kind = {kind!r} is not an event kind{suggest(kind, _EVENT_KEYS)}: use one of {', '.join(_EVENT_KEYS)}"
        )
    required, optional = _EVENT_KEYS[kind]
    _check_keys(where, d, ("kind", *required), optional)
    args = {k: d[k] for k in (*required, *optional) if k in d}
    if kind == "requirements":
        for side in ("add", "remove"):
            if side in args:
                items = args[side]
                if not isinstance(items, list):
                    raise CheckerError(f"{where}.{side} = {items!r} is not a list: write [] or a list of requirements")
                if any(isinstance(x, str) for x in items):
                    raise CheckerError(f"{where}: the requirement change of {d['graph']!r} is {_OLD_FORMAT}")
                args[side] = tuple(constraint_from_json(x, where=f"{where}.{side}[{i}]") for i, x in enumerate(items))
    cls = RequirementChange if kind == "requirements" else LoadChange if kind == "load" else _SIMPLE_EVENTS[kind]
    return _build(where, cls, args)  # type: ignore[return-value]


def constraint_from_json(data: object, *, where: str = "requirement") -> Constraint:
    """The requirement or preference :func:`constraint_to_json` wrote, checked as when a scenario builds it."""
    d = _mapping(where, data, '{"requirement": "capacity", "resource": "memory", "amount": 250}')
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
    return _build(where, cls, _mapping(where, data, example))


def _mapping(where: str, d: object, example: str) -> dict[str, Any]:
    if not isinstance(d, dict):
        raise CheckerError(f"{where} = {d!r} is not a JSON object: write e.g. {example}")
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

