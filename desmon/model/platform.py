"""Computational platforms and the devices (sensors) attached to them."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Mapping

from desmon.errors import ModelError

__all__ = ["Device", "Platform", "check_name", "check_amount"]


def check_name(what: str, name: object) -> str:
    """Return ``name`` if it is a usable identifier-like string, else raise ModelError."""
    if not isinstance(name, str) or not name.strip():
        raise ModelError(f"{what} name {name!r} is not a non-empty string: give every {what} a name")
    if any(ch in name for ch in "/\n\t"):
        raise ModelError(f"{what} name {name!r} contains '/', a newline or a tab: use letters, digits, '_' or '-'")
    return name


def check_amount(what: str, value: object, *, integer: bool = False) -> float:
    """Return ``value`` as a finite non-negative number, else raise ModelError naming ``what``."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ModelError(f"{what} = {value!r} is not a number: give a non-negative number")
    if not math.isfinite(value) or value < 0:
        raise ModelError(f"{what} = {value!r} is negative or not finite: give a non-negative number")
    if integer and int(value) != value:
        raise ModelError(f"{what} = {value!r} is not a whole number: give a count such as 1, 2, 6")
    return value


def _frozen_mapping(what: str, mapping: Mapping[str, object] | None) -> tuple[tuple[str, object], ...]:
    if mapping is None:
        return ()
    if not isinstance(mapping, Mapping):
        raise ModelError(f"{what} must be a mapping of names to values, got {type(mapping).__name__}")
    return tuple(sorted((check_name(what, k), v) for k, v in mapping.items()))


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

    def matches(self, kind: str, vendor: str | None = None, version: str | None = None) -> bool:
        """True if this device is of ``kind`` (and of ``vendor`` / ``version`` when given)."""
        return (
            self.kind == kind
            and (vendor is None or self.vendor == vendor)
            and (version is None or self.version == version)
        )


@dataclass(frozen=True, slots=True)
class Platform:
    """A computational platform of the robot.

    ``capacities`` maps a consumable resource (``memory`` in MB) to its size;
    ``attributes`` are symbolic facts (``os``, ``arch``); ``properties`` are numbers
    (``link_latency_ms``) that Minimum / Maximum requirements compare against;
    ``preference`` orders acceptable platforms (higher first) where a scenario wants
    something other than declaration order.
    """

    name: str
    capacities: tuple[tuple[str, float], ...] = ()
    attributes: tuple[tuple[str, object], ...] = ()
    properties: tuple[tuple[str, float], ...] = ()
    preference: float = 0.0

    def __post_init__(self) -> None:
        check_name("platform", self.name)
        for res, amount in self.capacities:
            check_amount(f"platform {self.name!r} capacity {res!r}", amount)
        for prop, value in self.properties:
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ModelError(
                    f"platform {self.name!r} property {prop!r} = {value!r} is not a finite number: "
                    "put symbolic facts in attributes, numbers in properties"
                )

    @classmethod
    def make(
        cls,
        name: str,
        *,
        memory: float | None = None,
        capacities: Mapping[str, float] | None = None,
        attributes: Mapping[str, object] | None = None,
        properties: Mapping[str, float] | None = None,
        preference: float = 0.0,
    ) -> "Platform":
        """Build a platform from keyword arguments (``memory`` is the ``memory`` capacity in MB)."""
        caps = dict(capacities or {})
        if memory is not None:
            caps["memory"] = memory
        return cls(
            name=name,
            capacities=_frozen_mapping(f"platform {name!r} capacity", caps),  # type: ignore[arg-type]
            attributes=_frozen_mapping(f"platform {name!r} attribute", attributes),
            properties=_frozen_mapping(f"platform {name!r} property", properties),  # type: ignore[arg-type]
            preference=preference,
        )

    def capacity(self, resource: str) -> float | None:
        for res, amount in self.capacities:
            if res == resource:
                return amount
        return None

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
