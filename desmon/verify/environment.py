"""The checker's environment: its event alphabet, one place.

A transition starts with one environment event, chosen among those the scenario's
:class:`~desmon.verify.bounds.Bounds` enable in the current state; the system's
reaction follows. :data:`EVENT_KINDS` names the kinds (the report counts per kind) and
:func:`enabled_events` lists a state's events in the order every engine explores them
(the order fixes which shortest counterexample a search reports).

The environment is a list of bounded *variables* (:func:`variables`: the context, each
bounded device, platform, load and on-demand platform, each requirement change), and
each kind of variable enables its events (``_EVENTS``). Both engines walk that list:
the direct engine through :func:`enabled_events`, the table engine by turning each
variable into array operations on its environment codes
(:class:`desmon.verify.table.encoding.Events`), so the alphabet and its order are
written once, here.

Adding an event kind to the checker's alphabet: the kind is a class of
:mod:`desmon.model.events` (its name, JSON and facts travel with it, see docs/design.md
"Recipe: a new event kind"); here it takes a ``Bounds`` field that bounds it
(:mod:`desmon.verify.bounds`, validated there), a place in :data:`ALPHABET`, a kind of
variable in :func:`variables` and its events in ``_EVENTS``. The direct engine and the
symmetry reduction then explore it (:meth:`Symmetry.rename_event
<desmon.verify.symmetry.Symmetry.rename_event>` must map it if it names a platform).
The table engine refuses a kind of variable it has no array operations for
(:class:`~desmon.verify.table.encoding.Events` raises
:class:`~desmon.errors.TableUnsupported`), so ``--engine auto`` falls back to the
direct engine until it has them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from desmon.model.events import (
    ActionChange,
    DeviceFail,
    DeviceRepair,
    Event,
    LoadChange,
    PlatformDown,
    PlatformJoin,
    PlatformLeave,
    PlatformUp,
    RequirementChange,
)
from desmon.verify.state import Key

if TYPE_CHECKING:  # pragma: no cover
    from desmon.verify.bounds import Bounds

__all__ = ["ALPHABET", "EVENT_KINDS", "Variable", "variables", "can_fail", "enabled_events"]

#: the event classes the checker explores, in exploration (and report) order
ALPHABET = (ActionChange, DeviceFail, DeviceRepair, PlatformDown, PlatformUp, LoadChange, PlatformJoin, PlatformLeave, RequirementChange)
#: their kinds (:attr:`desmon.model.events.Event.kind`), in report order
EVENT_KINDS = tuple(cls.kind for cls in ALPHABET)


@dataclass(frozen=True, slots=True)
class Variable:
    """One bounded variable of the environment, whose events a state may enable: the
    context (``kind`` "action"), a device, a platform that may go down, a platform's load,
    an on-demand platform that joins and leaves, a requirement change (``subject``: the
    device's or platform's name, or the :class:`RequirementChange`)."""

    kind: str
    subject: Any = None


def variables(b: "Bounds") -> tuple[Variable, ...]:
    """The environment's variables in exploration order: the context, the bounded devices,
    the platforms that may go down, the loaded platforms, the on-demand platforms, the
    requirement changes. :func:`enabled_events` and the table engine's event encoding
    (:class:`desmon.verify.table.encoding.Events`) both walk this list."""
    return (
        Variable("action"),
        *(Variable("device", d) for d in b.devices),
        *(Variable("platform", p) for p in b.platforms),
        *(Variable("load", p) for p in b.loads),
        *(Variable("join", p) for p in b.joins),
        *(Variable("requirements", c) for c in b.requirement_changes),
    )


def can_fail(b: "Bounds", key: Key) -> bool:
    """Whether ``key`` has room for another failure under ``b.max_failures`` (absent
    on-demand platforms are not failures)."""
    down = len(key.down) - sum(1 for p in b.joins if p in key.down) if b.joins else len(key.down)
    return b.max_failures is None or len(key.failed) + down < b.max_failures


def enabled_events(b: "Bounds", key: Key) -> list[Event]:
    """Every environment event ``b`` enables in state ``key``, in exploration order
    (:func:`variables`): action changes, device failures and repairs, platforms down and
    up, load steps, then on-demand platforms joining or leaving and requirement changes."""
    room = can_fail(b, key)
    out: list[Event] = []
    for v in variables(b):
        out += _EVENTS[v.kind](b, key, v.subject, room)
    return out


def _action_events(b: "Bounds", key: Key, _subject: None, _room: bool) -> list[Event]:
    return [ActionChange(a) for a in b.action_moves(key.context)]


def _device_events(b: "Bounds", key: Key, d: str, room: bool) -> list[Event]:
    if d in key.failed:
        return [DeviceRepair(d)] if b.repair else []
    return [DeviceFail(d)] if room else []


def _platform_events(b: "Bounds", key: Key, p: str, room: bool) -> list[Event]:
    if p in key.down:
        return [PlatformUp(p)] if b.repair else []
    return [PlatformDown(p)] if room else []


def _load_events(b: "Bounds", key: Key, p: str, _room: bool) -> list[Event]:
    """A load step up and down (to the neighbouring bounded levels) on loaded platform ``p``."""
    lv = b.loads[p]
    i = lv.index(dict(dict(key.loads).get(p, ())).get(b.load_resource, 0))
    out: list[Event] = []
    if i + 1 < len(lv):
        out.append(LoadChange(p, lv[i + 1], b.load_resource))
    if i > 0:
        out.append(LoadChange(p, lv[i - 1], b.load_resource))
    return out


def _join_events(b: "Bounds", key: Key, p: str, _room: bool) -> list[Event]:
    return [PlatformJoin(p) if p in key.down else PlatformLeave(p)]


def _requirement_events(b: "Bounds", key: Key, change: RequirementChange, _room: bool) -> list[Event]:
    return [change]


#: the events of each kind of variable
_EVENTS = {
    "action": _action_events, "device": _device_events, "platform": _platform_events, "load": _load_events,
    "join": _join_events, "requirements": _requirement_events,
}
