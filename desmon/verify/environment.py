"""The checker's environment: its event alphabet, one place.

A transition starts with one environment event, chosen among those the scenario's
:class:`~desmon.verify.bounds.Bounds` enable in the current state; the system's
reaction follows. :data:`EVENT_KINDS` names the kinds (the report counts per kind) and
:func:`enabled_events` lists a state's events in the order every engine explores them
(the order fixes which shortest counterexample a search reports).

Adding an event kind to the checker's alphabet: the kind is a class of
:mod:`desmon.model.events` (its name, JSON and facts travel with it, see docs/design.md
"Recipe: a new event kind"); here it takes a ``Bounds`` field that bounds it
(:mod:`desmon.verify.bounds`, validated there), a place in :data:`ALPHABET` and one
``_<kind>_events`` function called from :func:`enabled_events`. The direct engine and
the symmetry reduction then explore it (:meth:`Symmetry.rename_event
<desmon.verify.symmetry.Symmetry.rename_event>` must map it if it names a platform).
The table engine encodes the environment as numbers (:class:`desmon.verify.table.encoding.Env`
and ``Events``, mirroring this order); until it encodes the new kind, make
:func:`desmon.verify.table.search.table_unsupported` name the new bounds so ``--engine auto``
falls back to the direct engine.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

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

__all__ = ["ALPHABET", "EVENT_KINDS", "enabled_events"]

#: the event classes the checker explores, in exploration (and report) order
ALPHABET = (ActionChange, DeviceFail, DeviceRepair, PlatformDown, PlatformUp, LoadChange, PlatformJoin, PlatformLeave, RequirementChange)
#: their kinds (:attr:`desmon.model.events.Event.kind`), in report order
EVENT_KINDS = tuple(cls.kind for cls in ALPHABET)


def enabled_events(b: "Bounds", key: Key) -> list[Event]:
    """Every environment event ``b`` enables in state ``key``, in exploration order:
    action changes, device failures and repairs, platforms down and up, load steps, then
    on-demand platforms joining or leaving and requirement changes (absent on-demand
    platforms are not failures)."""
    down = len(key.down) - sum(1 for p in b.joins if p in key.down) if b.joins else len(key.down)
    can_fail = b.max_failures is None or len(key.failed) + down < b.max_failures
    out = [*_action_events(b, key), *_device_events(b, key, can_fail), *_platform_events(b, key, can_fail), *_load_events(b, key)]
    if b.joins:
        out += [PlatformJoin(p) if p in key.down else PlatformLeave(p) for p in b.joins]
    if b.requirement_changes:
        out += b.requirement_changes
    return out


def _action_events(b: "Bounds", key: Key) -> list[Event]:
    return [ActionChange(a) for a in b.action_moves(key.context)]


def _device_events(b: "Bounds", key: Key, can_fail: bool) -> list[Event]:
    out: list[Event] = []
    for d in b.devices:
        if d in key.failed:
            if b.repair:
                out.append(DeviceRepair(d))
        elif can_fail:
            out.append(DeviceFail(d))
    return out


def _platform_events(b: "Bounds", key: Key, can_fail: bool) -> list[Event]:
    out: list[Event] = []
    for p in b.platforms:
        if p in key.down:
            if b.repair:
                out.append(PlatformUp(p))
        elif can_fail:
            out.append(PlatformDown(p))
    return out


def _load_events(b: "Bounds", key: Key) -> list[Event]:
    """A load step up and down (to the neighbouring bounded levels) on each loaded platform."""
    if not b.loads:
        return []
    out: list[Event] = []
    cur = {p: dict(items).get(b.load_resource, 0) for p, items in key.loads}
    for p, lv in b.loads.items():
        i = lv.index(cur.get(p, 0))
        if i + 1 < len(lv):
            out.append(LoadChange(p, lv[i + 1], b.load_resource))
        if i > 0:
            out.append(LoadChange(p, lv[i - 1], b.load_resource))
    return out
