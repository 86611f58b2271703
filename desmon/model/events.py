"""Environment events: what happens to the robot, whoever generates it.

The scripted driver, the SimPy world, the checker and the fuzzer all speak these; the
context monitor (:mod:`desmon.deployment.monitor`) turns them into repository facts.

Each kind is one class carrying its behaviour: its ``kind`` (the name in JSON and in
the checker's report), its description (``__str__``), what it names that a model may
lack (:meth:`Event.problem`), the facts it writes and what that stimulates
(:meth:`Event.write`), its ``role`` in the SimPy world (a task ``action``, a ``fault``,
a ``load`` or a run-time ``change``) and its JSON shape (:meth:`Event.to_json`,
:meth:`Event.json_keys`, :meth:`Event.json_args`). A class that sets ``kind`` registers
itself (:meth:`Event.kinds` lists them in definition order); every list of kinds is
derived from that registry. Device and platform events share their behaviour through
:class:`DeviceEvent` and :class:`PlatformEvent`. docs/design.md ("Recipe: a new event
kind") says how to add one.
"""

from __future__ import annotations

import math
from dataclasses import MISSING, dataclass, fields
from typing import TYPE_CHECKING, Any, Callable, ClassVar, Iterable, Protocol, TypeVar

from desmon.errors import CheckerError, ModelError
from desmon.model.checks import check_items, check_name, check_number, is_plain_name, strict_init, suggest
from desmon.model.requirements import Capacity, Constraint, constraint_types, declared_order
from desmon.model.system import action_problem, constraint_problem

if TYPE_CHECKING:  # pragma: no cover
    from desmon.model.system import SystemModel

__all__ = [
    "Event", "DeviceEvent", "PlatformEvent", "Effects", "InsertPort",
    "ActionChange", "DeviceFail", "DeviceRepair", "PlatformDown", "PlatformUp", "LoadChange",
    "RequirementChange", "PlatformJoin", "PlatformLeave", "Together", "event_kind", "event_types",
]

S = TypeVar("S")

#: kind -> class, filled by :meth:`Event.__init_subclass__` (in definition order)
_REGISTRY: dict[str, type["Event"]] = {}


class Effects:
    """What a written fact means for the deployment core, as the context monitor builds
    it (:class:`desmon.deployment.monitor.Stimulus`): :meth:`Event.write` returns one of
    these four. The monitor passes its own (interned) implementation."""

    nothing: Any = None
    context_changed: Any = None

    def platform_changed(self, platform: str) -> Any:  # pragma: no cover - a port
        raise NotImplementedError

    def specs_changed(self, hosts: tuple[str, ...], graph: str) -> Any:  # pragma: no cover - a port
        raise NotImplementedError

    def merged(self, first: Any, second: Any) -> Any:  # pragma: no cover - a port
        """What two writes together mean: one stimulus for one reaction (:class:`Together`)."""
        raise NotImplementedError


class InsertPort(Protocol):
    """The Insert facts the context monitor writes; each returns whether anything changed."""

    def set_context(self, context: str) -> bool: ...

    def set_device_working(self, device: str, working: bool) -> str | None:
        """Returns the platform whose HAS_DEVICE edge changed, or None."""

    def set_platform_up(self, platform: str, up: bool) -> bool: ...

    def set_load(self, platform: str, resource: str, amount: float) -> bool: ...

    def change_requirements(self, change: RequirementChange) -> tuple[str, ...] | None:
        """Apply a requirement change; returns the platforms its graph is deployed on, or
        None if the requirements did not change."""


class Event:
    """The base of every environment event kind (see the module docstring).

    A subclass is a frozen dataclass that sets ``kind`` (and ``role``), writes its
    facts in :meth:`write` and, if it names parts of the model, says what is missing in
    :meth:`problem`. Setting ``kind`` registers the class.
    """

    __slots__ = ()
    #: the kind's name in JSON and in the checker's counts ('' for an abstract family)
    kind: ClassVar[str] = ""
    #: where the SimPy world takes it: 'action' (the task), 'fault' (``World.faults``),
    #: 'load' (``World.loads``) or 'change' (``World.changes``)
    role: ClassVar[str] = ""

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        kind = cls.__dict__.get("kind")
        if kind:  # a dataclass(slots=True) re-creates the class: the later one wins
            _REGISTRY[kind] = cls

    # -- the registry -----------------------------------------------------------------
    @staticmethod
    def kinds() -> tuple[type["Event"], ...]:
        """Every registered event class, in definition order."""
        return tuple(_REGISTRY.values())

    @staticmethod
    def of_kind(kind: object) -> type["Event"] | None:
        """The class of ``kind`` (its JSON name), or None."""
        return _REGISTRY.get(kind) if isinstance(kind, str) else None

    @classmethod
    def unregister(cls) -> None:
        """Forget this kind (a kind defined for a test only)."""
        if _REGISTRY.get(cls.kind) is cls:
            del _REGISTRY[cls.kind]

    # -- behaviour ----------------------------------------------------------------------
    def write(self, store: "InsertPort", effects: Effects) -> Any:
        """Write the facts this event implies through ``store`` (the Insert port) and
        return what changed, as one of ``effects``."""
        raise ModelError(f"not an environment event: {self!r}")

    def problem(self, model: "SystemModel", others: Iterable["Event"] = ()) -> str | None:
        """What this event names that ``model`` does not have (None if nothing)."""
        return None

    # -- JSON ---------------------------------------------------------------------------
    @classmethod
    def json_keys(cls) -> tuple[tuple[str, ...], tuple[str, ...]]:
        """The keys of its JSON besides ``kind``: (required, optional); by default its
        dataclass fields, those with a default optional."""
        fs = fields(cls)  # type: ignore[arg-type]
        required = tuple(f.name for f in fs if f.default is MISSING and f.default_factory is MISSING)
        return required, tuple(f.name for f in fs if f.name not in required)

    def to_json(self, value_to_json: Callable[[Any], Any]) -> dict[str, Any]:
        """``{"kind": kind, key: value, ...}``; ``value_to_json`` writes a model value
        (a requirement) that is not plain JSON."""
        required, optional = self.json_keys()
        return {"kind": self.kind, **{k: getattr(self, k) for k in (*required, *optional)}}

    @classmethod
    def json_args(cls, args: dict[str, Any], value_from_json: Callable[..., Any], where: str) -> dict[str, Any]:
        """The constructor arguments from the JSON keys (``args``, already checked for
        unknown and missing keys); ``value_from_json(data, where=...)`` reads a model value."""
        return args


def event_kind(event: Event) -> str:
    """``action``, ``device_fail``, ``device_repair``, ``platform_down``, ``platform_up``,
    ``load``, ``requirements``, ``platform_join`` or ``platform_leave`` (or a kind
    registered elsewhere)."""
    return event.kind


def event_types() -> tuple[type[Event], ...]:
    """Every environment event type (the registry, in definition order)."""
    return Event.kinds()


class DeviceEvent(Event):
    """A device stops or starts working (``working``); the family's behaviour."""

    __slots__ = ()
    role = "fault"
    #: whether the device works after the event
    working: ClassVar[bool] = False
    device: str

    def __post_init__(self) -> None:
        check_name(f"{type(self).__name__} device", self.device)

    def write(self, store: "InsertPort", effects: Effects) -> Any:
        platform = store.set_device_working(self.device, self.working)
        return effects.platform_changed(platform) if platform else effects.nothing

    def problem(self, model: "SystemModel", others: Iterable[Event] = ()) -> str | None:
        devices = [d.name for d in model.devices]
        if self.device in devices:
            return None
        platforms = [p.name for p in model.platforms]
        other = f": {self.device!r} is a platform (use PlatformDown / PlatformUp)" if self.device in platforms else ""
        return f"{self} names unknown device {self.device!r}{suggest(self.device, devices)}{other} (devices: {', '.join(devices) or 'none'})"


class PlatformEvent(Event):
    """A platform goes up or down (``up``); on-demand ones join and leave (``on_demand``)."""

    __slots__ = ()
    role = "fault"
    #: whether the platform is up after the event
    up: ClassVar[bool] = False
    #: True: only an on-demand platform; False: only a fixed one
    on_demand: ClassVar[bool] = False
    platform: str

    def __post_init__(self) -> None:
        check_name(f"{type(self).__name__} platform", self.platform)

    def write(self, store: "InsertPort", effects: Effects) -> Any:
        changed = store.set_platform_up(self.platform, self.up)
        return effects.platform_changed(self.platform) if changed else effects.nothing

    def problem(self, model: "SystemModel", others: Iterable[Event] = ()) -> str | None:
        problem = _platform_problem(self, self.platform, model)
        if problem is not None:
            return problem
        if model.platform(self.platform).on_demand and not self.on_demand:
            return f"{self}: platform {self.platform!r} is on demand: it joins and leaves (PlatformJoin / PlatformLeave) instead of going up and down"
        if self.on_demand and not model.platform(self.platform).on_demand:
            return f"{self}: platform {self.platform!r} is not on demand, so it cannot join or leave: declare it with on_demand=True, or use PlatformUp / PlatformDown"
        return None


def _platform_problem(ev: Event, platform: str, model: "SystemModel") -> str | None:
    """``ev`` names a platform ``model`` lacks (None if it has it)."""
    platforms = [p.name for p in model.platforms]
    if platform in platforms:
        return None
    devices = [d.name for d in model.devices]
    other = f": {platform!r} is a device (use DeviceFail / DeviceRepair)" if platform in devices else ""
    return f"{ev} names unknown platform {platform!r}{suggest(platform, platforms)}{other} (platforms: {', '.join(platforms)})"


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class ActionChange(Event):
    """The robot's action context became ``action`` (as the context monitor recognises it)."""

    kind = "action"
    role = "action"
    action: str

    def __post_init__(self) -> None:
        check_name("ActionChange action", self.action)

    def __str__(self) -> str:
        return f"action {self.action}"

    def write(self, store: "InsertPort", effects: Effects) -> Any:
        return effects.context_changed if store.set_context(self.action) else effects.nothing

    def problem(self, model: "SystemModel", others: Iterable[Event] = ()) -> str | None:
        return action_problem(model, self.action)


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class DeviceFail(DeviceEvent):
    kind = "device_fail"
    working = False
    device: str

    def __str__(self) -> str:
        return f"device {self.device} fails"


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class DeviceRepair(DeviceEvent):
    kind = "device_repair"
    working = True
    device: str

    def __str__(self) -> str:
        return f"device {self.device} repaired"


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class PlatformDown(PlatformEvent):
    kind = "platform_down"
    up = False
    platform: str

    def __str__(self) -> str:
        return f"platform {self.platform} down"


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class PlatformUp(PlatformEvent):
    kind = "platform_up"
    up = True
    platform: str

    def __str__(self) -> str:
        return f"platform {self.platform} up"


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class LoadChange(Event):
    """Background consumption of ``resource`` on ``platform`` became ``amount``."""

    kind = "load"
    role = "load"
    platform: str
    amount: float
    resource: str = "memory"

    def __post_init__(self) -> None:
        amount = self.amount
        if is_plain_name(self.platform) and is_plain_name(self.resource) and type(amount) is float and 0.0 <= amount < math.inf:
            return  # what the checks below accept (a load walk builds one every step): no message built
        check_name("LoadChange platform", self.platform)
        check_name(f"LoadChange({self.platform!r}) resource", self.resource)
        check_number(f"load on {self.platform!r} {self.resource}", self.amount)

    def __str__(self) -> str:
        return f"load {self.platform} {self.resource}={self.amount:g}"

    def write(self, store: "InsertPort", effects: Effects) -> Any:
        changed = store.set_load(self.platform, self.resource, self.amount)
        return effects.platform_changed(self.platform) if changed else effects.nothing

    def problem(self, model: "SystemModel", others: Iterable[Event] = ()) -> str | None:
        problem = _platform_problem(self, self.platform, model)
        if problem is not None:
            return problem
        caps = [r for r, _ in model.platform(self.platform).capacities]
        if self.resource not in caps:
            return (
                f"{self}: platform {self.platform!r} has no {self.resource!r} capacity{suggest(self.resource, caps)}, so the load "
                f"would change nothing: fix the resource or declare the capacity (capacities of {self.platform!r}: {', '.join(caps) or 'none'})"
            )
        return None


#: how an older desmon wrote a requirement change (by its description only)
_OLD_FORMAT = (
    "written by an older desmon, which kept a requirement change by its description only: "
    "re-run desmon verify --json to write it in full"
)


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class RequirementChange(Event):
    """The deployment requirements of ``graph`` change at run time: ``remove`` these
    requirements (or preferences), then ``add`` these. A change is a remove plus an add,
    e.g. ``RequirementChange("combined", add=(Capacity("memory", 350),),
    remove=(Capacity("memory", 250),))`` when the robot speeds up (an added Capacity
    replaces the graph's Capacity on its resource in any case: ``remove`` may leave it
    out). ``label`` names the change in reports (default: the change itself)."""

    kind = "requirements"
    role = "change"
    graph: str
    add: tuple[Constraint, ...] = ()
    remove: tuple[Constraint, ...] = ()
    label: str = ""

    def __post_init__(self) -> None:
        check_name("RequirementChange graph", self.graph)
        example = "(Capacity('memory', 350),)"
        add = check_items(f"RequirementChange({self.graph!r}) add", self.add, constraint_types(), example=example)
        remove = check_items(f"RequirementChange({self.graph!r}) remove", self.remove, constraint_types(), example=example)
        if not add and not remove:
            raise ModelError(f"RequirementChange({self.graph!r}) adds and removes nothing: give add=(...) and/or remove=(...)")
        for what, items in (("adds", add), ("removes", remove)):
            twice = [r.describe() for i, r in enumerate(items) if r in items[:i]]
            if twice:
                raise ModelError(f"RequirementChange({self.graph!r}) {what} {twice[0]} twice: give it once")
        resources = [r.resource for r in add if isinstance(r, Capacity)]
        twice_on = sorted({x for x in resources if resources.count(x) > 1})
        if twice_on:  # (the graph would end with both: a graph consumes one amount of a resource)
            raise ModelError(
                f"RequirementChange({self.graph!r}) adds two Capacity requirements on {twice_on[0]!r}: a graph consumes one "
                f"amount of a resource; give one Capacity({twice_on[0]!r}, TOTAL)"
            )
        both = [r.describe() for r in add if r in remove]
        if both:
            raise ModelError(f"RequirementChange({self.graph!r}) both adds and removes {', '.join(both)}: give it once")
        if not isinstance(self.label, str) or "\n" in self.label:
            raise ModelError(f"RequirementChange({self.graph!r}) label {self.label!r} is not one line of text")
        object.__setattr__(self, "add", add)
        object.__setattr__(self, "remove", remove)

    def apply(self, requirements: tuple[Constraint, ...], declared: tuple[Constraint, ...]) -> tuple[Constraint, ...]:
        """The requirements after this change: removed ones dropped, added ones kept once.
        An added Capacity replaces the one the graph has on its resource then, removed or
        not: a graph consumes one amount of each resource. ``declared`` is what the graph
        declared: the result is in :func:`declared_order`, so one set of requirements is one
        tuple however the changes that led to it came (a change and its reverse give back
        the declared tuple, and the checker counts one state for it)."""
        resized = {r.resource for r in self.add if isinstance(r, Capacity)}
        kept = tuple(r for r in requirements if r not in self.remove and not (isinstance(r, Capacity) and r.resource in resized and r not in self.add))
        return declared_order(kept + tuple(r for r in self.add if r not in kept), declared)

    def __str__(self) -> str:
        if self.label:
            return f"requirements of {self.graph}: {self.label}"
        parts = [f"-{r.describe()}" for r in self.remove] + [f"+{r.describe()}" for r in self.add]
        return f"requirements of {self.graph}: {' '.join(parts)}"

    def write(self, store: "InsertPort", effects: Effects) -> Any:
        hosts = store.change_requirements(self)
        return effects.nothing if hosts is None else effects.specs_changed(hosts, self.graph)

    def problem(self, model: "SystemModel", others: Iterable[Event] = ()) -> str | None:
        spec = model.spec(self.graph)
        if spec is None:
            known = [s.graph for s in model.specs]
            return f"{self} names graph {self.graph!r} with no deployment specification{suggest(self.graph, known)} (specifications: {', '.join(known) or 'none'})"
        # a change may remove what the specification declares or what a change adds
        removable = list(spec.requirements) + [r for o in others if isinstance(o, RequirementChange) and o.graph == self.graph for r in o.add]
        for r in self.remove:
            if r not in removable:
                have = ", ".join(x.describe() for x in spec.requirements) or "none"
                return f"{self} removes {r.describe()}, which {self.graph!r} never has (declared: {have}; nor does any change add it): remove a requirement it has"
        for r in self.add:
            problem = constraint_problem(model, self.graph, r)
            if problem is not None:
                return f"{self} adds {r.describe()} but {problem}"
        return None

    @classmethod
    def json_keys(cls) -> tuple[tuple[str, ...], tuple[str, ...]]:
        return ("graph",), ("label", "add", "remove")

    def to_json(self, value_to_json: Callable[[Any], Any]) -> dict[str, Any]:
        return {
            "kind": self.kind, "graph": self.graph, "label": self.label,
            "add": [value_to_json(r) for r in self.add], "remove": [value_to_json(r) for r in self.remove],
        }

    @classmethod
    def json_args(cls, args: dict[str, Any], value_from_json: Callable[..., Any], where: str) -> dict[str, Any]:
        for side in ("add", "remove"):
            if side in args:
                items = args[side]
                if not isinstance(items, list):
                    raise CheckerError(f"{where}.{side} = {items!r} is not a list: write [] or a list of requirements")
                if any(isinstance(x, str) for x in items):
                    raise CheckerError(f"{where}: the requirement change of {args['graph']!r} is {_OLD_FORMAT}")
                args[side] = tuple(value_from_json(x, where=f"{where}.{side}[{i}]") for i, x in enumerate(items))
        return args


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class PlatformJoin(PlatformEvent):
    """An on-demand platform (a leased edge or cloud server) joins and can host graphs."""

    kind = "platform_join"
    role = "change"
    up = True
    on_demand = True
    platform: str

    def __str__(self) -> str:
        return f"platform {self.platform} joins"


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class PlatformLeave(PlatformEvent):
    """An on-demand platform leaves (its lease ends): whatever ran on it is gone."""

    kind = "platform_leave"
    role = "change"
    up = False
    on_demand = True
    platform: str

    def __str__(self) -> str:
        return f"platform {self.platform} leaves"


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class Together(Event):
    """Two changes of different variables that one reaction answers: the world's deployer
    takes every change that came since its last reaction (two at one instant, or those
    that came while a start waited), which the checker explores with
    ``Bounds(together=True)``. It writes both and stimulates what either does."""

    kind = "together"
    first: Event
    second: Event

    def __post_init__(self) -> None:
        for name in ("first", "second"):
            part = getattr(self, name)
            if not isinstance(part, Event) or isinstance(part, Together):
                raise ModelError(f"Together {name} {part!r}: give an environment event of one variable (an action, a fault, a load, ...)")
        one = _variable_of(self.first)
        if one is not None and one == _variable_of(self.second):
            raise ModelError(
                f"Together of '{self.first}' and '{self.second}': both change {' '.join(map(str, one))}, and one reaction's two "
                "changes are of different variables (the later one alone would stand): give them to two reactions"
            )

    def __str__(self) -> str:
        return f"{self.first} + {self.second}"

    def write(self, store: "InsertPort", effects: Effects) -> Any:
        return effects.merged(self.first.write(store, effects), self.second.write(store, effects))

    def problem(self, model: "SystemModel", others: Iterable[Event] = ()) -> str | None:
        return self.first.problem(model, others) or self.second.problem(model, others)

    def to_json(self, value_to_json: Callable[[Any], Any]) -> dict[str, Any]:
        return {"kind": self.kind, "first": self.first.to_json(value_to_json), "second": self.second.to_json(value_to_json)}

    @classmethod
    def json_args(cls, args: dict[str, Any], value_from_json: Callable[..., Any], where: str) -> dict[str, Any]:
        for k in ("first", "second"):
            if not (isinstance(args[k], dict) and "kind" in args[k]):
                raise CheckerError(f'{where}.{k} = {args[k]!r} is not an event: write e.g. {{"kind": "action", "action": "grasp"}}')
        return {k: value_from_json(args[k], where=f"{where}.{k}") for k in ("first", "second")}


def _variable_of(event: Event) -> tuple[str, ...] | None:
    """What ``event`` changes, for the built-in kinds (None for another kind): the context,
    a device, a platform, or a platform's load of one resource."""
    if isinstance(event, ActionChange):
        return ("the context",)
    if isinstance(event, DeviceEvent):
        return ("device", event.device)
    if isinstance(event, PlatformEvent):
        return ("platform", event.platform)
    if isinstance(event, LoadChange):
        return ("the load of", event.platform, event.resource)
    return None
