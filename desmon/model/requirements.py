"""DepSL requirements (the OMG deployment-specification kinds) and deployment specifications.

The semantics of each kind (docs/design.md §4) is implemented once, in
:mod:`desmon.deployment.validity`; this module is pure vocabulary and validation.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Iterable

from desmon.errors import ModelError
from desmon.model.checks import check_items, check_keywords, check_name, check_number, check_value, strict_init, suggest

__all__ = [
    "Quantity",
    "Capacity",
    "Minimum",
    "Maximum",
    "Attribute",
    "Selection",
    "Option",
    "Requirement",
    "REQUIREMENT_KINDS",
    "make_requirement",
    "DeploymentSpec",
    "PLATFORM_HAS",
    "Preference",
    "PREFERENCE_KINDS",
    "make_preference",
    "Constraint",
    "Reads",
]

#: The Attribute name that means "the platform has a working device of this kind" (R1).
PLATFORM_HAS = "platform_has"


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class Quantity:
    """At least ``count`` working devices of ``device_kind`` on the platform (R2)."""

    device_kind: str
    count: int

    def __post_init__(self) -> None:
        check_name("Quantity device kind", self.device_kind)
        check_number(f"Quantity({self.device_kind}) count", self.count, integer=True)
        if self.count < 1:
            raise ModelError(f"Quantity({self.device_kind}) count = {self.count!r} always holds: give a count >= 1 or drop the requirement")

    def describe(self) -> str:
        return f"Quantity({self.device_kind} >= {self.count:g})"


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class Capacity:
    """``amount`` of ``resource`` free on the platform; a deployed graph consumes it (R3)."""

    resource: str
    amount: float

    def __post_init__(self) -> None:
        check_name("Capacity resource", self.resource)
        check_number(f"Capacity({self.resource}) amount", self.amount)

    def describe(self) -> str:
        unit = " MB" if self.resource == "memory" else ""
        return f"Capacity({self.resource} >= {self.amount:g}{unit})"


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class Minimum:
    """The platform's numeric ``prop`` is at least ``value``."""

    prop: str
    value: float

    def __post_init__(self) -> None:
        check_name("Minimum property", self.prop)
        check_number(f"Minimum({self.prop}) value", self.value, low=None)

    def describe(self) -> str:
        return f"Minimum({self.prop} >= {self.value:g})"


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class Maximum:
    """The platform's numeric ``prop`` is at most ``value`` (e.g. link latency)."""

    prop: str
    value: float

    def __post_init__(self) -> None:
        check_name("Maximum property", self.prop)
        check_number(f"Maximum({self.prop}) value", self.value, low=None)

    def describe(self) -> str:
        return f"Maximum({self.prop} <= {self.value:g})"


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class Attribute:
    """The platform has attribute ``name`` equal to ``value``.

    ``Attribute("platform_has", kind)`` means: a working device of that kind is attached (R1).
    """

    name: str
    value: str

    def __post_init__(self) -> None:
        check_name("Attribute name", self.name)
        if self.name == PLATFORM_HAS:
            check_name("Attribute(platform_has) device kind", self.value)
        else:
            check_value(f"Attribute({self.name}) value", self.value)

    def describe(self) -> str:
        if self.name == PLATFORM_HAS:
            return f"Attribute(platform_has {self.value})"
        return f"Attribute({self.name} = {self.value})"


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class Option:
    """One alternative of a Selection: a device (kind, optionally vendor) or an attribute value.

    Parsed from ``"tactile_pad"``, ``"tactile_pad@weiss"`` or ``"os=linux"``.
    """

    device_kind: str | None = None
    vendor: str | None = None
    attribute: str | None = None
    value: str | None = None

    def __post_init__(self) -> None:
        if (self.device_kind is None) == (self.attribute is None):
            raise ModelError(
                f"Selection option {self!r} must name either a device kind or an attribute: "
                "write Option.parse('kind'), Option.parse('kind@vendor') or Option.parse('attr=value')"
            )
        if self.device_kind is not None:
            check_name("Selection device kind", self.device_kind)
            if self.vendor is not None:
                check_name(f"Selection option {self.device_kind!r} vendor", self.vendor)
            if self.value is not None:
                raise ModelError(f"Selection option {self.device_kind!r} has a value {self.value!r} but no attribute: drop it")
        else:
            check_name("Selection attribute", self.attribute)
            check_value(f"Selection option {self.attribute!r} value", self.value)
            if self.vendor is not None:
                raise ModelError(f"Selection option {self.attribute}={self.value} has a vendor {self.vendor!r}: vendors belong to devices")

    @classmethod
    def parse(cls, text: str) -> "Option":
        if not isinstance(text, str) or not text.strip():
            raise ModelError(
                f"Selection option {text!r} is not a non-empty string: write 'kind', 'kind@vendor' or 'attr=value'"
            )
        if "=" in text:
            attr, _, value = text.partition("=")
            if not value.strip():
                raise ModelError(f"Selection option {text!r} has no value after '=': write 'attr=value', e.g. 'os=linux'")
            return cls(attribute=check_name("Selection attribute", attr.strip()), value=value.strip())
        kind, _, vendor = text.partition("@")
        if "@" in text and (not vendor.strip() or "@" in vendor):
            raise ModelError(f"Selection option {text!r}: write 'kind@vendor' with one '@' and a vendor after it, or just 'kind'")
        return cls(device_kind=check_name("Selection device kind", kind.strip()), vendor=vendor.strip() or None)

    def describe(self) -> str:
        if self.attribute is not None:
            return f"{self.attribute}={self.value}"
        return f"{self.device_kind}@{self.vendor}" if self.vendor else str(self.device_kind)


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class Selection:
    """At least ``at_least`` of the listed alternatives are available on the platform."""

    options: tuple[Option, ...]
    at_least: int = 1

    def __post_init__(self) -> None:
        options = check_items("Selection options", self.options, Option, example="(Option.parse('tactile_pad@weiss'), ...)")
        object.__setattr__(self, "options", options)
        if not self.options:
            raise ModelError("Selection has no options: list at least one alternative, e.g. 'tactile_pad@weiss'")
        check_number("Selection at_least", self.at_least, integer=True)
        if self.at_least < 1:
            raise ModelError("Selection at_least = 0 always holds: give at_least >= 1 or drop the requirement")
        if self.at_least > len(self.options):
            raise ModelError(
                f"Selection at_least = {self.at_least} but only {len(self.options)} options "
                f"({', '.join(o.describe() for o in self.options)}): lower at_least or add options"
            )

    def describe(self) -> str:
        return f"Selection({self.at_least} of {', '.join(o.describe() for o in self.options)})"


@dataclass(frozen=True, slots=True)
class Reads:
    """The requirement a perception graph's inputs make: a device of ``kind`` it reads is
    readable (docs/design.md §6, the Control rules' reading rule).

    Nobody writes it: :class:`~desmon.model.system.SystemModel` derives one per device
    kind a graph's sensor components read (:attr:`DeploymentSpec.reads`). ``devices``
    are the declared devices of that kind as ``(device, platform)`` pairs, in
    declaration order. On a platform that hosts some of them the graph reads its own
    (one must work there); elsewhere it reads any of them, so one must work on a
    platform that is up. The first half is a fact of the platform alone and is checked
    with its other requirements; the second is read from the hosting platforms'
    facts (:func:`desmon.deployment.validity.unreadable_inputs`).
    """

    kind: str
    devices: tuple[tuple[str, str], ...]
    #: The platforms hosting a device of this kind, in declaration order, without repeats
    #: (derived from ``devices`` once: every validity question asks it).
    hosts: tuple[str, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "hosts", tuple(dict.fromkeys(p for _d, p in self.devices)))

    def describe(self) -> str:
        return f"reads {self.kind}"


Requirement = Quantity | Capacity | Minimum | Maximum | Attribute | Selection

#: Soft preference kinds and their arguments (see :class:`Preference`).
PREFERENCE_KINDS = ("vendor", "attribute", "most_free", "least_loaded", "colocate", "spread")
_PREFERENCE_USAGE = {
    "vendor": "write ('vendor', device_kind, vendor, weight=1)",
    "attribute": "write ('attribute', name, value, weight=1)",
    "most_free": "write ('most_free', resource, weight=1)",
    "least_loaded": "write ('least_loaded', resource, weight=1)",
    "colocate": "write ('colocate', graph, graph, ..., weight=1)",
    "spread": "write ('spread', weight=1)",
}
_PREFERENCE_ARITY = {"vendor": (2, 2), "attribute": (2, 2), "most_free": (1, 1), "least_loaded": (1, 1), "colocate": (1, 64), "spread": (0, 0)}


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class Preference:
    """A soft DepSL constraint: it never rejects a platform, it scores it.

    Hard requirements decide which platforms are *acceptable*; the preferences of a
    specification order them: each acceptable platform scores the sum over preferences
    of ``weight`` times a term in [0, 1] (:func:`desmon.deployment.validity.preference_term`):

    ``vendor(kind, vendor)``
        1 if a working ``kind`` device of ``vendor`` is attached, else 0;
    ``attribute(name, value)``
        1 if the platform's attribute ``name`` equals ``value``, else 0;
    ``most_free(resource)``
        the free fraction of ``resource`` (the graph's own share counts as free);
    ``least_loaded(resource)``
        1 minus the background-load fraction of ``resource``;
    ``colocate(graph, ...)``
        1 if one of the named graphs is deployed on the platform, else 0;
    ``spread()``
        1 / (1 + number of other graphs deployed on the platform).

    Higher scores come first; ties keep the platform ``preference`` then declaration
    order, as without preferences.
    """

    kind: str
    args: tuple[str, ...] = ()
    weight: float = 1.0

    def __post_init__(self) -> None:
        if not isinstance(self.kind, str) or self.kind not in _PREFERENCE_USAGE:
            raise ModelError(
                f"unknown preference kind {self.kind!r}{suggest(self.kind, PREFERENCE_KINDS)}: use one of {', '.join(PREFERENCE_KINDS)}"
            )
        if isinstance(self.args, str) or not isinstance(self.args, (tuple, list)):
            raise ModelError(f"preference {self.kind!r} args {self.args!r} is not a tuple of names: {_PREFERENCE_USAGE[self.kind]}")
        args = tuple(self.args)
        low, high = _PREFERENCE_ARITY[self.kind]
        if not low <= len(args) <= high:
            shown = ", ".join(repr(a) for a in args) or "nothing"
            raise ModelError(f"preference {self.kind!r} got {len(args)} argument(s) ({shown}): {_PREFERENCE_USAGE[self.kind]}")
        for i, a in enumerate(args):
            if self.kind == "attribute" and i == 1:
                check_value(f"preference attribute({args[0]!r}) value", a)
            else:
                check_name(f"preference {self.kind!r} argument", a)
        object.__setattr__(self, "args", tuple(str(a) for a in args))
        check_number(f"preference {self.kind!r} weight", self.weight, positive=True)

    def describe(self) -> str:
        inner = {
            "vendor": lambda a: f"{a[0]}@{a[1]}",
            "attribute": lambda a: f"{a[0]}={a[1]}",
        }.get(self.kind, lambda a: ", ".join(a))(self.args)
        return f"prefer {self.kind}({inner}) x{self.weight:g}"


#: What a deployment specification lists: hard requirements and soft preferences.
Constraint = Requirement | Preference


def make_preference(kind: str, *args: object, weight: object = 1.0, **kwargs: object) -> Preference:
    """Build a preference from DepSL-style words: ``make_preference("vendor", "tactile_pad", "weiss", weight=2)``."""
    if not isinstance(kind, str):
        raise ModelError(f"preference kind {kind!r} is not a string: use one of {', '.join(PREFERENCE_KINDS)}")
    key = kind.lower().lstrip(":")
    if key not in _PREFERENCE_USAGE:
        raise ModelError(f"unknown preference kind {kind!r}{suggest(key, PREFERENCE_KINDS)}: use one of {', '.join(PREFERENCE_KINDS)}")
    check_keywords(f"preference {kind!r}", kwargs, ("weight",), usage=_PREFERENCE_USAGE[key])
    if key == "colocate" and len(args) == 1 and isinstance(args[0], (list, tuple)):
        args = tuple(args[0])
    return Preference(key, tuple(args), weight)  # type: ignore[arg-type]

REQUIREMENT_KINDS = ("quantity", "capacity", "minimum", "maximum", "attribute", "selection")
_REQUIREMENT_TYPES = (Quantity, Capacity, Minimum, Maximum, Attribute, Selection)


def make_requirement(kind: str, *args: object, **kwargs: object) -> Requirement:
    """Build a requirement from DepSL-style words: ``make_requirement("capacity", "memory", 250)``.

    Kinds: quantity(kind, n), capacity(resource, amount), minimum(prop, v),
    maximum(prop, v), attribute(name, value), selection(option, ..., at_least=1).
    """
    if not isinstance(kind, str):
        raise ModelError(f"requirement kind {kind!r} is not a string: use one of {', '.join(REQUIREMENT_KINDS)}")
    key = kind.lower().lstrip(":")
    if key not in _USAGE:
        raise ModelError(f"unknown requirement kind {kind!r}{suggest(key, REQUIREMENT_KINDS)}: use one of {', '.join(REQUIREMENT_KINDS)}")
    check_keywords(f"requirement {kind!r}", kwargs, ("at_least",) if key == "selection" else (), usage=_USAGE[key])
    if key != "selection" and len(args) != 2:
        shown = ", ".join(repr(a) for a in args) or "nothing"
        raise ModelError(f"requirement {kind!r} got {len(args)} argument(s) ({shown}) but takes 2: {_USAGE[key]}")
    if key == "quantity":
        return Quantity(*args)  # type: ignore[arg-type]
    if key == "capacity":
        return Capacity(*args)  # type: ignore[arg-type]
    if key == "minimum":
        return Minimum(*args)  # type: ignore[arg-type]
    if key == "maximum":
        return Maximum(*args)  # type: ignore[arg-type]
    if key == "attribute":
        name, value = args
        return Attribute(name.lstrip(":") if isinstance(name, str) else name, value)  # type: ignore[arg-type]
    opts: Iterable[object] = args
    if len(args) == 1 and isinstance(args[0], (list, tuple)):
        opts = args[0]
    return Selection(tuple(Option.parse(o) for o in opts), kwargs.get("at_least", 1))  # type: ignore[arg-type]


_USAGE = {
    "quantity": "write ('quantity', device_kind, count)",
    "capacity": "write ('capacity', resource, amount)",
    "minimum": "write ('minimum', property, value)",
    "maximum": "write ('maximum', property, value)",
    "attribute": "write ('attribute', name, value)",
    "selection": "write ('selection', option, option, ..., at_least=1)",
}


_CONSTRAINT_TYPES = (*_REQUIREMENT_TYPES, Preference)


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class DeploymentSpec:
    """DepSL: how the perception graph ``graph`` may be deployed.

    ``fixed_platform`` is the EXECUTABLE_ON platform of a fixed deployment. The
    Capacity requirements say both what must be free and what the deployed graph consumes.
    """

    graph: str
    requirements: tuple[Constraint, ...] = ()
    fixed_platform: str | None = None
    #: The rebalancing threshold: a valid deployment moves to a better-scoring platform
    #: only when the score gain exceeds it (hysteresis); None never moves a valid one.
    rebalance: float | None = None
    #: What the graph's inputs require (one :class:`Reads` per device kind its sensor
    #: components read that some device provides), derived by the
    #: :class:`~desmon.model.system.SystemModel` from its graphs and devices: not part of
    #: what a user writes, nor of the specification's identity (equality, hash).
    reads: tuple[Reads, ...] = field(default=(), compare=False)

    def __post_init__(self) -> None:
        check_name("deployment specification graph", self.graph)
        reqs = check_items(
            f"deployment specification of {self.graph!r} requirements", self.requirements, _CONSTRAINT_TYPES,
            example="(Capacity('memory', 150),) or add_constraint('capacity', 'memory', 150)",
        )
        object.__setattr__(self, "requirements", reqs)
        if self.fixed_platform is not None:
            check_name(f"fixed platform of {self.graph!r}", self.fixed_platform)
        if self.rebalance is not None:
            check_number(f"rebalance min_gain of {self.graph!r}", self.rebalance)
        reads = tuple(self.reads) if isinstance(self.reads, (tuple, list)) else self.reads
        if not isinstance(reads, tuple) or not all(isinstance(r, Reads) for r in reads):
            raise ModelError(
                f"deployment specification of {self.graph!r} reads = {self.reads!r}: leave it out "
                "(the system model derives it from the graph's sensor components and the devices)"
            )
        object.__setattr__(self, "reads", reads)

    def rebalance_problem(self) -> str | None:
        """Why this specification's ``rebalance`` can never move anything (None if it can,
        or if it does not rebalance): with no preference every platform scores 0.

        The one rule the DSL (:meth:`~desmon.model.dsl.SpecBuilder.build`) and the model
        (:class:`~desmon.model.system.SystemModel`) apply to a *declared* specification.
        It is not checked here: the specification a run derives from a declared one after
        a :class:`~desmon.model.events.RequirementChange` may lose its last preference
        for a while (and get one back later), and then rebalancing rightly does nothing.
        """
        if self.rebalance is None or any(isinstance(r, Preference) for r in self.requirements):
            return None
        return (
            f"deployment specification of {self.graph!r} rebalances (min_gain {self.rebalance:g}) but has no "
            "preference to score platforms by, so it would never move anything: add a preference "
            "(prefer(...) in the DSL, Preference(...) in requirements) or drop rebalance"
        )

    @property
    def hard(self) -> tuple[Requirement, ...]:
        """The hard requirements (what decides acceptable)."""
        return tuple(r for r in self.requirements if not isinstance(r, Preference))

    @property
    def preferences(self) -> tuple[Preference, ...]:
        """The soft preferences (what orders the acceptable platforms)."""
        return tuple(r for r in self.requirements if isinstance(r, Preference))

    def consumption(self) -> tuple[tuple[str, float], ...]:
        """What a deployment of this spec consumes, per resource (sum of its Capacity amounts)."""
        use: dict[str, float] = {}
        for req in self.requirements:
            if isinstance(req, Capacity):
                use[req.resource] = use.get(req.resource, 0.0) + req.amount
        return tuple(sorted(use.items()))
