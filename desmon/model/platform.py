"""Computational platforms and the devices (sensors) attached to them."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping

from desmon.errors import ModelError
from desmon.model.checks import (
    PLATFORM_HAS, check_amount, check_flag, check_name, check_number, check_pairs, check_value, is_numeric_text, strict_call, strict_init,
)

__all__ = ["Device", "Platform", "check_name", "check_amount"]


def _pairs(what: str, value: object, example: str) -> tuple[tuple[str, object], ...]:
    if value is None:
        return ()
    return check_pairs(what, value, example=example)  # type: ignore[return-value]


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class Device:
    """A sensor attached to a platform: ``kind`` is what perception graphs read (e.g. ``force_sensor``)."""

    name: str
    kind: str
    platform: str
    vendor: str = "generic"
    version: str = "1"

    def __post_init__(self) -> None:
        check_name("device", self.name)
        check_name(f"device {self.name!r} kind", self.kind)
        check_name(f"device {self.name!r} platform", self.platform)
        check_name(f"device {self.name!r} vendor", self.vendor)
        check_name(f"device {self.name!r} version", self.version)

    def matches(self, kind: str, vendor: str | None = None, version: str | None = None) -> bool:
        """True if this device is of ``kind`` (and of ``vendor`` / ``version`` when given)."""
        return (
            self.kind == kind
            and (vendor is None or self.vendor == vendor)
            and (version is None or self.version == version)
        )


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class Platform:
    """A computational platform of the robot.

    ``capacities`` maps a consumable resource (``memory`` in MB) to its size;
    ``attributes`` are symbolic facts (``os``, ``arch``); ``properties`` are numbers
    (``link_latency_ms``) that Minimum / Maximum requirements compare against;
    ``preference`` orders acceptable platforms (higher first) where a scenario wants
    something other than declaration order.

    An ``on_demand`` platform (a leased edge or cloud server) is absent until a
    :class:`~desmon.model.events.PlatformJoin` and gone again after a
    :class:`~desmon.model.events.PlatformLeave`; ``startup_s`` is how long it takes to
    join after it is requested (the SimPy world's lease). Its network latency is a
    property like any other (e.g. ``latency_ms``), for Maximum requirements to limit.
    """

    name: str
    capacities: tuple[tuple[str, float], ...] = ()
    attributes: tuple[tuple[str, object], ...] = ()
    properties: tuple[tuple[str, float], ...] = ()
    preference: float = 0.0
    on_demand: bool = False
    startup_s: float = 0.0

    def __post_init__(self) -> None:
        check_name("platform", self.name)
        where = f"platform {self.name!r}"
        caps = _pairs(f"{where} capacities", self.capacities, "{'memory': 512}")
        for res, amount in caps:
            check_amount(f"{where} capacity {res!r}", amount)
        attrs = _pairs(f"{where} attributes", self.attributes, "{'os': 'linux'}")
        for key, value in attrs:
            check_value(f"{where} attribute {key!r}", value)
            if key == PLATFORM_HAS:  # Attribute('platform_has', KIND) asks for a working attached device, never this
                raise ModelError(
                    f"{where} attribute {key!r} is the name Attribute({key!r}, KIND) reserves for an attached working "
                    f"device: attach the device (platform(...).device(NAME, kind={value!r})) or name the attribute otherwise"
                )
        props = _pairs(f"{where} properties", self.properties, "{'link_latency_ms': 2.0}")
        for prop, value in props:
            if isinstance(value, str) and not is_numeric_text(value):
                raise ModelError(
                    f"{where} property {prop!r} = {value!r} is not a number: "
                    "put symbolic facts in attributes, numbers in properties"
                )
            check_number(f"{where} property {prop!r}", value, low=None)
        check_number(f"{where} preference", self.preference, low=None)
        check_flag(f"{where} on_demand", self.on_demand)
        check_number(f"{where} startup_s", self.startup_s, unit=" of seconds")
        if self.startup_s and not self.on_demand:
            raise ModelError(f"{where} has startup_s = {self.startup_s:g} but is not on_demand: only a leased platform starts up; set on_demand=True or drop startup_s")
        object.__setattr__(self, "capacities", caps)
        object.__setattr__(self, "attributes", attrs)
        object.__setattr__(self, "properties", props)

    @classmethod
    @strict_call(ModelError, "platform(...)")
    def make(
        cls,
        name: str,
        *,
        memory: float | None = None,
        capacities: Mapping[str, float] | None = None,
        attributes: Mapping[str, object] | None = None,
        properties: Mapping[str, float] | None = None,
        preference: float = 0.0,
        on_demand: bool = False,
        startup_s: float = 0.0,
    ) -> "Platform":
        """Build a platform from keyword arguments (``memory`` is the ``memory`` capacity in MB)."""
        check_name("platform", name)
        caps = _pairs(f"platform {name!r} capacities", capacities, "{'memory': 512}")
        if memory is not None:
            if any(res == "memory" for res, _ in caps):
                raise ModelError(
                    f"platform {name!r} gives memory twice (memory={memory!r} and capacities['memory']): give it once"
                )
            caps += (("memory", memory),)
        return cls(
            name=name,
            capacities=tuple(sorted(caps)),  # type: ignore[arg-type]
            attributes=tuple(sorted(_pairs(f"platform {name!r} attributes", attributes, "{'os': 'linux'}"))),
            properties=tuple(sorted(_pairs(f"platform {name!r} properties", properties, "{'link_latency_ms': 2.0}"))),  # type: ignore[arg-type]
            preference=preference,
            on_demand=on_demand,
            startup_s=startup_s,
        )

    def capacity(self, resource: str) -> float | None:
        for res, amount in self.capacities:
            if res == resource:
                return amount
        return None

    def capacity_or_unbounded(self, resource: str) -> float:
        """:meth:`capacity`, infinite where the platform declares none (a declared 0 stays 0)."""
        amount = self.capacity(resource)
        return math.inf if amount is None else amount

    def attribute(self, name: str) -> object | None:
        for key, value in self.attributes:
            if key == name:
                return value
        return None

    def prop(self, name: str) -> float | None:
        for key, value in self.properties:
            if key == name:
                return value
        return None
