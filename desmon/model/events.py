"""Environment events: what happens to the robot, whoever generates it.

The scripted driver, the SimPy world, the checker and the fuzzer all speak these; the
context monitor (:mod:`desmon.deployment.monitor`) turns them into repository facts.
"""

from __future__ import annotations

from dataclasses import dataclass

from desmon.errors import ModelError
from desmon.model.checks import check_name, check_number, strict_init

__all__ = ["ActionChange", "DeviceFail", "DeviceRepair", "PlatformDown", "PlatformUp", "LoadChange", "Event", "event_kind"]


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


Event = ActionChange | DeviceFail | DeviceRepair | PlatformDown | PlatformUp | LoadChange


def event_kind(event: Event) -> str:
    """``action``, ``device_fail``, ``device_repair``, ``platform_down``, ``platform_up`` or ``load``."""
    return _KINDS[type(event)]


_KINDS = {
    ActionChange: "action",
    DeviceFail: "device_fail",
    DeviceRepair: "device_repair",
    PlatformDown: "platform_down",
    PlatformUp: "platform_up",
    LoadChange: "load",
}
