"""Environment events: what happens to the robot, whoever generates it.

The scripted driver, the SimPy world, the checker and the fuzzer all speak these; the
context monitor (:mod:`desmon.deployment.monitor`) turns them into repository facts.
"""

from __future__ import annotations

from dataclasses import dataclass

from desmon.errors import ModelError
from desmon.model.checks import check_items, check_name, check_number, strict_init
from desmon.model.requirements import _CONSTRAINT_TYPES, Constraint

__all__ = [
    "ActionChange", "DeviceFail", "DeviceRepair", "PlatformDown", "PlatformUp", "LoadChange",
    "RequirementChange", "PlatformJoin", "PlatformLeave", "Event", "event_kind",
]


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class ActionChange:
    """The robot's action context became ``action`` (as the context monitor recognises it)."""

    action: str

    def __post_init__(self) -> None:
        check_name("ActionChange action", self.action)

    def __str__(self) -> str:
        return f"action {self.action}"


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class DeviceFail:
    device: str

    def __post_init__(self) -> None:
        check_name("DeviceFail device", self.device)

    def __str__(self) -> str:
        return f"device {self.device} fails"


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class DeviceRepair:
    device: str

    def __post_init__(self) -> None:
        check_name("DeviceRepair device", self.device)

    def __str__(self) -> str:
        return f"device {self.device} repaired"


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class PlatformDown:
    platform: str

    def __post_init__(self) -> None:
        check_name("PlatformDown platform", self.platform)

    def __str__(self) -> str:
        return f"platform {self.platform} down"


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class PlatformUp:
    platform: str

    def __post_init__(self) -> None:
        check_name("PlatformUp platform", self.platform)

    def __str__(self) -> str:
        return f"platform {self.platform} up"


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class LoadChange:
    """Background consumption of ``resource`` on ``platform`` became ``amount``."""

    platform: str
    amount: float
    resource: str = "memory"

    def __post_init__(self) -> None:
        check_name("LoadChange platform", self.platform)
        check_name(f"LoadChange({self.platform!r}) resource", self.resource)
        check_number(f"load on {self.platform!r} {self.resource}", self.amount)

    def __str__(self) -> str:
        return f"load {self.platform} {self.resource}={self.amount:g}"


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class RequirementChange:
    """The deployment requirements of ``graph`` change at run time: ``remove`` these
    requirements (or preferences), then ``add`` these. A change is a remove plus an add,
    e.g. ``RequirementChange("combined", add=(Capacity("memory", 350),),
    remove=(Capacity("memory", 250),))`` when the robot speeds up. ``label`` names the
    change in reports (default: the change itself)."""

    graph: str
    add: tuple[Constraint, ...] = ()
    remove: tuple[Constraint, ...] = ()
    label: str = ""

    def __post_init__(self) -> None:
        check_name("RequirementChange graph", self.graph)
        example = "(Capacity('memory', 350),)"
        add = check_items(f"RequirementChange({self.graph!r}) add", self.add, _CONSTRAINT_TYPES, example=example)
        remove = check_items(f"RequirementChange({self.graph!r}) remove", self.remove, _CONSTRAINT_TYPES, example=example)
        if not add and not remove:
            raise ModelError(f"RequirementChange({self.graph!r}) adds and removes nothing: give add=(...) and/or remove=(...)")
        for what, items in (("adds", add), ("removes", remove)):
            twice = [r.describe() for i, r in enumerate(items) if r in items[:i]]
            if twice:
                raise ModelError(f"RequirementChange({self.graph!r}) {what} {twice[0]} twice: give it once")
        both = [r.describe() for r in add if r in remove]
        if both:
            raise ModelError(f"RequirementChange({self.graph!r}) both adds and removes {', '.join(both)}: give it once")
        if not isinstance(self.label, str) or "\n" in self.label:
            raise ModelError(f"RequirementChange({self.graph!r}) label {self.label!r} is not one line of text")
        object.__setattr__(self, "add", add)
        object.__setattr__(self, "remove", remove)

    def apply(self, requirements: tuple[Constraint, ...]) -> tuple[Constraint, ...]:
        """The requirements after this change (removed ones dropped, added ones appended once)."""
        kept = tuple(r for r in requirements if r not in self.remove)
        return kept + tuple(r for r in self.add if r not in kept)

    def __str__(self) -> str:
        if self.label:
            return f"requirements of {self.graph}: {self.label}"
        parts = [f"-{r.describe()}" for r in self.remove] + [f"+{r.describe()}" for r in self.add]
        return f"requirements of {self.graph}: {' '.join(parts)}"


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class PlatformJoin:
    """An on-demand platform (a leased edge or cloud server) joins and can host graphs."""

    platform: str

    def __post_init__(self) -> None:
        check_name("PlatformJoin platform", self.platform)

    def __str__(self) -> str:
        return f"platform {self.platform} joins"


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class PlatformLeave:
    """An on-demand platform leaves (its lease ends): whatever ran on it is gone."""

    platform: str

    def __post_init__(self) -> None:
        check_name("PlatformLeave platform", self.platform)

    def __str__(self) -> str:
        return f"platform {self.platform} leaves"


Event = ActionChange | DeviceFail | DeviceRepair | PlatformDown | PlatformUp | LoadChange | RequirementChange | PlatformJoin | PlatformLeave


def event_kind(event: Event) -> str:
    """``action``, ``device_fail``, ``device_repair``, ``platform_down``, ``platform_up``,
    ``load``, ``requirements``, ``platform_join`` or ``platform_leave``."""
    return _KINDS[type(event)]


_KINDS = {
    ActionChange: "action",
    DeviceFail: "device_fail",
    DeviceRepair: "device_repair",
    PlatformDown: "platform_down",
    PlatformUp: "platform_up",
    LoadChange: "load",
    RequirementChange: "requirements",
    PlatformJoin: "platform_join",
    PlatformLeave: "platform_leave",
}
