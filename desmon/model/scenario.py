"""Scenarios: a model plus what happens to the robot, and the results it pins.

A scenario file is a Python script that builds a :class:`Scenario` with the DSL and
binds it to the module-level name ``scenario`` (see ``scenarios/coffee_handover.py``).
Engines read the parts they need: the scripted replay reads ``timeline``; the SimPy
world reads ``world`` (its own typed configuration); the checker reads ``checker``.
``expected`` pins results as data, and the tests assert them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Iterable, Mapping

from desmon.errors import ModelError
from desmon.model.checks import check_items, check_name, check_number, check_text, strict_init

from desmon.model.events import ActionChange, Event, event_types
from desmon.model.system import SystemModel

__all__ = ["TimedEvent", "Scenario", "EVENT_TYPES", "event_problem"]

#: Every environment event type (the kinds registered when this module was imported;
#: :func:`desmon.model.events.event_types` lists them as of now).
EVENT_TYPES = event_types()


def event_problem(ev: Event, model: SystemModel, others: Iterable[Event] = ()) -> str | None:
    """What ``ev`` names that ``model`` does not have (None if it names only known things).

    One rule for every place an event is written: a scenario's ``initial`` and
    ``timeline``, the SimPy world's scripted faults and loads, and the checker's bounds.
    ``others`` are the other events written beside it (a requirement change may remove
    what another change adds). Each kind says it (:meth:`Event.problem`).
    """
    return ev.problem(model, others)


def _looks_like_time(label: str) -> bool:
    try:
        float(label)
    except ValueError:
        return False
    return True


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class TimedEvent:
    """``event`` happens at ``time`` seconds; ``label`` names the moment (e.g. ``t1``)."""

    time: float
    event: Event
    label: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.event, Event):
            raise ModelError(
                f"TimedEvent at t={self.time!r}: {self.event!r} is not an environment event: "
                "write e.g. TimedEvent(1.0, ActionChange('grasp')) or TimedEvent(5.0, DeviceFail('lwr_wrench'))"
            )
        check_number(f"time of {self.event}", self.time, unit=" of seconds (times are seconds >= 0)")
        check_text(f"label of {self.event} at t={self.time:g}", self.label)
        if not self.label.isprintable():  # a newline would forge a line of desmon replay's report
            raise ModelError(f"label {self.label!r} of {self.event} at t={self.time:g} is not one line of printable text: write e.g. 't1'")

@strict_init(ModelError)
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
        (times >= 0, sorted; labels unique, none reading as a number, holding a comma or
        with outer spaces: each one an --at can name);
    ``world``
        a ``desmon.sim.world.World`` for ``desmon run`` (task steps, slips, faults,
        latencies, loads, horizon); without one, ``desmon run`` derives it from the timeline;
    ``checker``
        a ``desmon.verify.Bounds`` (or a dict of its fields) for ``desmon verify / fuzz``;
    ``expected``
        pinned results as data; the tests assert them.

    ``scenarios/coffee_handover.py`` uses all of these. Every field is checked when the
    scenario is built, and the world and the bounds are checked against the model then
    (through their ``check_against(scenario)``).
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
        check_name("scenario", self.name)
        where = f"scenario {self.name!r}"
        if not isinstance(self.model, SystemModel):
            raise ModelError(f"{where}: model must be a SystemModel (use RobotBuilder(...).build())")
        initial = check_items(f"{where} initial", self.initial, event_types(), example="initial=(LoadChange('arm_pc', 300),)")
        timeline = check_items(
            f"{where} timeline", self.timeline, TimedEvent, example="timeline=(TimedEvent(0.0, ActionChange('grasp'), 't0'),)"
        )
        object.__setattr__(self, "initial", initial)
        object.__setattr__(self, "timeline", timeline)
        check_text(f"{where} description", self.description)
        if not isinstance(self.expected, Mapping):
            raise ModelError(f"{where}: expected = {self.expected!r} is not a mapping: write expected={{'desmon': {{...}}}}")
        events = list(initial) + [te.event for te in timeline]
        for ev in initial:
            if isinstance(ev, ActionChange):  # (set silently, no reaction would follow it: run and replay judged no deployment)
                raise ModelError(
                    f"{where} initial: {ev!r}: the robot's action is not a silent fact; begin the timeline with it, "
                    f"timeline=(TimedEvent(0.0, ActionChange({ev.action!r}), 't0'), ...), or set the checker's initial_action"
                )
            self._check_event(ev, events)
        last = 0.0
        labels: set[str] = set()
        for te in timeline:
            self._check_event(te.event, events)
            if te.label:
                _check_label(where, te.label, labels)
                labels.add(te.label)
            if te.time < last:
                raise ModelError(f"{where}: timeline event {te.event} at t={te.time} comes before t={last}: sort the timeline")
            last = te.time
        # the world and the checker bounds are typed by the layers above; each checks
        # itself against the model through ``check_against(scenario)`` when the scenario is built
        for part, what, fix in (
            ("world", "a desmon.sim.world.World", "World(task=..., horizon=...)"),
            ("checker", "a desmon.verify.Bounds", "Bounds(actions=..., devices=...)"),
        ):
            value = getattr(self, part)
            if value is None or (part == "checker" and isinstance(value, Mapping)):
                continue  # a dict of Bounds fields is built and checked by desmon.verify.bounds_of
            check = getattr(value, "check_against", None)
            if not callable(check):
                raise ModelError(f"{where}: {part} is a {type(value).__name__}, not {what}: write {part}={fix}")
            check(self)

    def _check_event(self, ev: Event, others: Iterable[Event] = ()) -> None:
        problem = event_problem(ev, self.model, others)
        if problem is not None:
            raise ModelError(f"scenario {self.name!r}: {problem}")


def _check_label(where: str, label: str, labels: set[str]) -> None:
    """A timeline label ``--at`` can name: no time, comma, outer space or leading ``-``,
    and none of ``labels`` (those before it)."""
    if _looks_like_time(label):
        raise ModelError(
            f"{where}: timeline label {label!r} reads as a time: --at {label} would mean the label, "
            f"not t={label} s; name the moment with a letter first, e.g. t{label}"
        )
    if "," in label or label != label.strip():
        fix = label.strip().replace(",", "_") or "t1"
        flaw = "holds a comma" if "," in label else "begins or ends with a space"
        raise ModelError(
            f"{where}: timeline label {label!r} {flaw}: --at reads a comma-separated list of labels, each "
            f"without its outer spaces, so it could never name this moment; write e.g. {fix!r}"
        )
    if label.startswith("-"):
        raise ModelError(
            f"{where}: timeline label {label!r} begins with '-': the command line reads --at {label} as "
            f"another option, so it could never name this moment; write e.g. {label.lstrip('-') or 't1'!r}"
        )
    if label in labels:
        raise ModelError(f"{where}: timeline label {label!r} is used twice: labels name one moment each")
