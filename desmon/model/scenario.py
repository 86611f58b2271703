"""Scenarios: a model plus what happens to the robot, and the results it pins.

A scenario file is a Python script that builds a :class:`Scenario` with the DSL and
binds it to the module-level name ``scenario`` (see ``scenarios/coffee_handover.py``).
Engines read the parts they need: the scripted replay reads ``timeline``; the SimPy
world reads ``world`` (its own typed configuration); the checker reads ``checker``.
``expected`` pins results as data, and the tests assert them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping

from desmon.errors import ModelError
from desmon.model.events import ActionChange, DeviceFail, DeviceRepair, Event, LoadChange, PlatformDown, PlatformUp
from desmon.model.actions import ACTIONS
from desmon.model.system import SystemModel

__all__ = ["TimedEvent", "Scenario"]


@dataclass(frozen=True, slots=True)
class TimedEvent:
    """``event`` happens at ``time`` seconds; ``label`` names the moment (e.g. ``t1``)."""

    time: float
    event: Event
    label: str = ""


@dataclass(frozen=True, slots=True)
class Scenario:
    """A runnable scenario.

    ``name``
        used in reports and file names;
    ``model``
        the robot: ``RobotBuilder(...).build()`` (or ``desmon.model.cob3.care_o_bot()``);
    ``initial``
        facts true before the first reaction, e.g. ``LoadChange("arm_pc", 300)``;
    ``timeline``
        scripted ``TimedEvent(time, event, label)`` s for ``desmon replay / explain / show``
        (times >= 0, sorted, labels unique);
    ``world``
        a ``desmon.sim.world.World`` for ``desmon run`` (task steps, slips, faults,
        latencies, loads, horizon); without one, ``desmon run`` derives it from the timeline;
    ``checker``
        a ``desmon.verify.Bounds`` (or a dict of its fields) for ``desmon verify / fuzz``;
    ``expected``
        pinned results as data; the tests assert them.

    ``scenarios/coffee_handover.py`` uses all of these.
    """

    name: str
    model: SystemModel
    timeline: tuple[TimedEvent, ...] = ()
    #: Facts that hold before anything happens (background loads, broken devices); they
    #: are written into the repository silently, before the first reaction.
    initial: tuple[Event, ...] = ()
    description: str = ""
    world: Any = None
    checker: Any = None
    expected: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not isinstance(self.model, SystemModel):
            raise ModelError(f"scenario {self.name!r}: model must be a SystemModel (use RobotBuilder(...).build())")
        last = 0.0
        labels: set[str] = set()
        devices = {d.name for d in self.model.devices}
        platforms = {p.name for p in self.model.platforms}
        for ev in self.initial:
            self._check_event(ev, devices, platforms)
        for te in self.timeline:
            self._check_event(te.event, devices, platforms)
            if not isinstance(te.time, (int, float)) or te.time != te.time or te.time < 0:
                raise ModelError(f"scenario {self.name!r}: timeline event {te.event} at t={te.time!r}: times are seconds >= 0")
            if te.label:
                if te.label in labels:
                    raise ModelError(f"scenario {self.name!r}: timeline label {te.label!r} is used twice: labels name one moment each")
                labels.add(te.label)
            if te.time < last:
                raise ModelError(
                    f"scenario {self.name!r}: timeline event {te.event} at t={te.time} comes before t={last}: sort the timeline"
                )
            last = te.time

    def _check_event(self, ev: Event, devices: set[str], platforms: set[str]) -> None:
        if not isinstance(ev, (ActionChange, DeviceFail, DeviceRepair, PlatformDown, PlatformUp, LoadChange)):
            raise ModelError(f"scenario {self.name!r}: {ev!r} is not an environment event")
        if isinstance(ev, ActionChange) and ev.action not in ACTIONS:
            raise ModelError(f"scenario {self.name!r}: unknown action {ev.action!r}; use one of {', '.join(ACTIONS)}")
        if isinstance(ev, LoadChange) and (
            isinstance(ev.amount, bool) or not isinstance(ev.amount, (int, float)) or not ev.amount >= 0
        ):
            raise ModelError(f"scenario {self.name!r}: load {ev.platform} {ev.resource}={ev.amount!r}: a load is a number >= 0")
        if isinstance(ev, (DeviceFail, DeviceRepair)) and ev.device not in devices:
            raise ModelError(f"scenario {self.name!r}: names unknown device {ev.device!r} (known: {sorted(devices)})")
        if isinstance(ev, (PlatformDown, PlatformUp, LoadChange)) and ev.platform not in platforms:
            raise ModelError(f"scenario {self.name!r}: names unknown platform {ev.platform!r} (known: {sorted(platforms)})")
