"""DepSL requirements (the OMG deployment-specification kinds) and deployment specifications.

**Each requirement kind is one class carrying its behaviour** (docs/design.md §2,
"Recipe: a new requirement kind"): its fields and their checks, :meth:`~Requirement.holds`
(the semantics of docs/design.md §4: ``None`` or the reason it fails on a platform),
:meth:`~Constraint.describe`, the DSL words (:attr:`~Requirement.word`,
:attr:`~Requirement.usage`), the model's facts problem (:meth:`~Constraint.platform_problem`,
:meth:`~Constraint.device_problem`), its JSON (:meth:`~Constraint.to_json`,
:meth:`~Requirement.json_args`), whether it reads only fixed facts or only devices, and
optionally its columns for the vectorised placement (:meth:`~Constraint.column_mask`;
``None``: no vector path). A class with a :attr:`~Requirement.word` registers itself
when it is defined: every list of kinds (the DSL's, the JSON's, what a deployment
specification accepts) is read from that registry.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from typing import TYPE_CHECKING, Any, Callable, Iterable, Sequence

from desmon.errors import CheckerError, ModelError
from desmon.model.checks import check_items, check_keywords, check_name, check_number, check_value, strict_init, suggest
from desmon.model.kinds import (
    PLATFORM_HAS,
    Columns,
    Constraint,
    Placing,
    Requirement,
    attribute_problem,
    device_kind_problem,
    others_using,
    property_problem,
    requirement_class,
    requirement_classes,
    requirement_kinds,
)

if TYPE_CHECKING:
    from desmon.model.platform import Device, Platform
    from desmon.model.state import PlatformState

__all__ = [
    "capacity_twice",
    "declared_order",
    "Quantity",
    "Capacity",
    "Minimum",
    "Maximum",
    "Attribute",
    "Selection",
    "overlapping_options",
    "Option",
    "Requirement",
    "REQUIREMENT_KINDS",
    "requirement_kinds",
    "requirement_class",
    "constraint_types",
    "make_requirement",
    "DeploymentSpec",
    "PLATFORM_HAS",
    "Preference",
    "PREFERENCE_KINDS",
    "make_preference",
    "Constraint",
    "Reads",
    "Placing",
    "fits",
    "slack",
    "CAPACITY_SLACK",
]


def _fmt(x: float) -> str:
    return f"{x:g}"


#: how far a sum of amounts may pass a capacity and still fit, per unit of the capacity (at
#: least 1): amounts a user writes in decimals add up in binary with rounding (1.2 - 0.4 is
#: 0.7999999999999999, 0.4 + 0.8 is 1.2000000000000002), and a rule that fits 0.4 and 0.8
#: into 1.2 must not hang on the last bit. Every engine compares capacities through
#: :func:`fits` and :func:`slack`: the Capacity requirement, its numpy columns, the
#: ``no-overcommit`` invariant, the memory over capacity, a fleet's admission, symmetry.
CAPACITY_SLACK = 1e-9


def slack(capacity: float) -> float:
    """What a sum of amounts may pass ``capacity`` by and still fit (:data:`CAPACITY_SLACK`)."""
    return CAPACITY_SLACK * max(1.0, abs(capacity))


def fits(used: float, capacity: float) -> bool:
    """Whether ``used``, a sum of amounts, stays within ``capacity`` (up to :func:`slack`)."""
    return used - capacity <= slack(capacity)


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class Quantity(Requirement):
    """At least ``count`` working devices of ``device_kind`` on the platform (R2)."""

    device_kind: str
    count: int

    word = "quantity"
    symmetric = True
    usage = "write ('quantity', device_kind, count)"

    def __post_init__(self) -> None:
        check_name("Quantity device kind", self.device_kind)
        check_number(f"Quantity({self.device_kind}) count", self.count, integer=True)
        object.__setattr__(self, "count", int(self.count))  # (2.0 is the count 2, and reads so)
        if self.count < 1:
            raise ModelError(f"Quantity({self.device_kind}) count = {self.count!r} always holds: give a count >= 1 or drop the requirement")

    def describe(self) -> str:
        return f"Quantity({self.device_kind} >= {self.count:g})"

    def holds(self, state: "PlatformState", graph: Placing) -> str | None:
        kind, need = self.device_kind, self.count
        have = 0
        for d in state.devices:  # counted up to what is needed (the whole count only for the reason)
            if d.kind == kind:
                have += 1
                if have >= need:
                    return None
        if have >= need:
            return None
        return f"{have} working {kind} device(s), needs {need}"

    def device_only(self) -> bool:
        return True

    def device_problem(self, devices: "tuple[Device, ...]") -> str | None:
        return device_kind_problem(self.device_kind, devices)

    def column_mask(self, cols: Columns, graph: Placing) -> Any:
        return cols.count(self.device_kind) >= self.count

    def column_keys(self, cols: Columns, rows: Any, graph: Placing) -> Any:
        return cols.count(self.device_kind)[rows]  # the text shows the count

    def column_numbers(self) -> tuple[object, ...]:
        return (self.count,)


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class Capacity(Requirement):
    """``amount`` of ``resource`` free on the platform; a deployed graph consumes it (R3)."""

    resource: str
    amount: float

    word = "capacity"
    symmetric = True
    usage = "write ('capacity', resource, amount)"
    texts_read_graph = True  # the graph placed: its own share is left out

    def __post_init__(self) -> None:
        check_name("Capacity resource", self.resource)
        check_number(f"Capacity({self.resource}) amount", self.amount)

    def describe(self) -> str:
        unit = " MB" if self.resource == "memory" else ""
        return f"Capacity({self.resource} >= {self.amount:g}{unit})"

    def holds(self, state: "PlatformState", graph: Placing) -> str | None:
        cap = state.platform.capacity(self.resource)
        if cap is None:
            return f"has no {self.resource} capacity"
        others = others_using(self.resource, state, graph)
        load = state.load_of(self.resource)
        free = cap - sum(a for _g, a in others) - load
        if self.amount - free <= slack(cap):  # (free >= amount, up to the rounding of the sums: fits)
            return None
        unit = " MB" if self.resource == "memory" else ""
        parts = [f"capacity {_fmt(cap)}"]
        parts += [f"used by {g} {_fmt(a)}" for g, a in others]
        parts.append(f"load {_fmt(load)}")
        return f"{_fmt(free)}{unit} free ({', '.join(parts)})"

    def best_state_decides(self) -> bool:
        return True  # loads and other graphs only take from the capacity

    def platform_problem(self, platforms: "tuple[Platform, ...]") -> str | None:
        declared = sorted({r for p in platforms for r, _ in p.capacities})
        if self.resource in declared:
            return None
        return (
            f"no platform declares a {self.resource!r} capacity{suggest(self.resource, declared)}: "
            f"add it to the platforms or fix the name (capacities: {', '.join(declared) or 'none'})"
        )

    def column_mask(self, cols: Columns, graph: Placing) -> Any:
        return cols.capacity(self, graph)

    def column_keys(self, cols: Columns, rows: Any, graph: Placing) -> Any:
        return cols.capacity_keys(self, rows, graph)

    def column_texts(self, cols: Columns, rows: Any, graph: Placing) -> list[str] | None:
        return cols.capacity_texts(self, rows, graph)  # type: ignore[no-any-return]

    def column_numbers(self) -> tuple[object, ...]:
        return (self.amount,)


class _PropertyBound(Requirement):
    """A bound on a platform's numeric property: :class:`Minimum` and :class:`Maximum`
    (``within`` says on which side of ``value`` a property holds)."""

    __slots__ = ()
    symmetric = True

    def within(self, value: Any) -> Any:
        """Whether ``value`` (a number, or a column of them) meets the bound."""
        raise NotImplementedError

    def holds(self, state: "PlatformState", graph: Placing) -> str | None:
        value = state.platform.prop(self.prop)  # type: ignore[attr-defined]
        if value is None:
            return f"has no property {self.prop!r}"  # type: ignore[attr-defined]
        return None if self.within(value) else f"{self.prop} is {_fmt(value)}"  # type: ignore[attr-defined]

    def reads_fixed_facts(self) -> bool:
        return True

    def platform_problem(self, platforms: "tuple[Platform, ...]") -> str | None:
        return property_problem(self.prop, platforms)  # type: ignore[attr-defined]

    def column_mask(self, cols: Columns, graph: Placing) -> Any:
        col = cols.prop(self.prop)  # type: ignore[attr-defined]
        return cols.none() if col is None else self.within(col)

    def column_keys(self, cols: Columns, rows: Any, graph: Placing) -> Any:
        return cols.prop_key(self.prop, rows)  # type: ignore[attr-defined]  # the text shows the value

    def column_numbers(self) -> tuple[object, ...]:
        return (self.value,)  # type: ignore[attr-defined]


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class Minimum(_PropertyBound):
    """The platform's numeric ``prop`` is at least ``value``."""

    prop: str
    value: float

    word = "minimum"
    usage = "write ('minimum', property, value)"

    def __post_init__(self) -> None:
        check_name("Minimum property", self.prop)
        check_number(f"Minimum({self.prop}) value", self.value, low=None)

    def describe(self) -> str:
        return f"Minimum({self.prop} >= {self.value:g})"

    def within(self, value: Any) -> Any:
        return value >= self.value


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class Maximum(_PropertyBound):
    """The platform's numeric ``prop`` is at most ``value`` (e.g. link latency)."""

    prop: str
    value: float

    word = "maximum"
    usage = "write ('maximum', property, value)"

    def __post_init__(self) -> None:
        check_name("Maximum property", self.prop)
        check_number(f"Maximum({self.prop}) value", self.value, low=None)

    def describe(self) -> str:
        return f"Maximum({self.prop} <= {self.value:g})"

    def within(self, value: Any) -> Any:
        return value <= self.value


@strict_init(ModelError)
@dataclass(frozen=True, slots=True, eq=False)
class Attribute(Requirement):
    """The platform has attribute ``name`` equal to ``value``.

    ``Attribute("platform_has", kind)`` means: a working device of that kind is attached (R1).
    A value is compared as text (a platform's ``gen=1.0`` is not ``1``), and so are two
    Attributes: ``Attribute("gen", 1)`` and ``Attribute("gen", 1.0)`` are two requirements,
    ``Attribute("gen", 1)`` and ``Attribute("gen", "1")`` one.
    """

    name: str
    value: str

    def __eq__(self, other: object) -> bool:
        return type(other) is type(self) and self.name == other.name and str(self.value) == str(other.value)  # type: ignore[attr-defined]

    def __hash__(self) -> int:
        return hash((Attribute, self.name, str(self.value)))

    word = "attribute"
    symmetric = True
    usage = "write ('attribute', name, value)"

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

    @classmethod
    def from_words(cls, *args: object, **kwargs: object) -> Requirement:
        if len(args) == 2 and isinstance(args[0], str):
            args = (args[0].lstrip(":"), args[1])  # ':platform_has' as the paper writes it
        return cls(*args, **kwargs)

    def holds(self, state: "PlatformState", graph: Placing) -> str | None:
        if self.name == PLATFORM_HAS:
            value = self.value
            for d in state.devices:  # any(d.kind == value ...), without a generator
                if d.kind == value:
                    return None
            return f"no working {value} attached"
        actual = state.platform.attribute(self.name)
        if actual is not None and str(actual) == str(self.value):
            return None
        return f"{self.name} is {actual!r}" if actual is not None else f"has no attribute {self.name!r}"

    def reads_fixed_facts(self) -> bool:
        return self.name != PLATFORM_HAS

    def device_only(self) -> bool:
        return self.name == PLATFORM_HAS

    def platform_problem(self, platforms: "tuple[Platform, ...]") -> str | None:
        return None if self.name == PLATFORM_HAS else attribute_problem(self.name, self.value, platforms)

    def device_problem(self, devices: "tuple[Device, ...]") -> str | None:
        return device_kind_problem(self.value, devices) if self.name == PLATFORM_HAS else None

    def column_mask(self, cols: Columns, graph: Placing) -> Any:
        if self.name == PLATFORM_HAS:
            return cols.count(self.value) > 0
        return cols.attr_is(self.name, self.value)

    def column_keys(self, cols: Columns, rows: Any, graph: Placing) -> Any:
        if self.name == PLATFORM_HAS:
            return cols.one_key(rows)  # one text
        return cols.attr_key(self.name, rows)  # the text shows the repr of the value


@strict_init(ModelError)
@dataclass(frozen=True, slots=True, eq=False)
class Option:
    """One alternative of a Selection: a device (kind, optionally vendor) or an attribute value.

    Parsed from ``"tactile_pad"``, ``"tactile_pad@weiss"`` or ``"os=linux"``. An attribute's
    value is compared as text, as :class:`Attribute`'s is (two options are equal when they
    mean the same).
    """

    device_kind: str | None = None
    vendor: str | None = None
    attribute: str | None = None
    value: str | None = None

    def _meaning(self) -> tuple:
        return (self.device_kind, self.vendor, self.attribute, None if self.attribute is None else str(self.value))

    def __eq__(self, other: object) -> bool:
        return type(other) is type(self) and self._meaning() == other._meaning()  # type: ignore[attr-defined]

    def __hash__(self) -> int:
        return hash((Option, self._meaning()))

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

    def holds(self, state: "PlatformState") -> bool:
        if self.attribute is not None:  # (a platform without the attribute meets no value of it, "None" included, as Attribute says)
            actual = state.platform.attribute(self.attribute)
            return actual is not None and str(actual) == str(self.value)
        return any(d.matches(self.device_kind or "", self.vendor) for d in state.devices)


def overlapping_options(options: Sequence["Option"]) -> "tuple[Option, Option] | None":
    """``(K, K@V)``: a device kind and the same kind by a vendor, both among ``options`` (one
    such device meets both, so a Selection with ``at_least`` above 1 would count it twice),
    or None."""
    for o in options:
        if o.device_kind is not None and o.vendor:
            wider = next((w for w in options if w.device_kind == o.device_kind and w.vendor is None), None)
            if wider is not None:
                return wider, o
    return None


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class Selection(Requirement):
    """At least ``at_least`` of the listed alternatives are available on the platform."""

    options: tuple[Option, ...]
    at_least: int = 1

    word = "selection"
    symmetric = True
    usage = "write ('selection', option, option, ..., at_least=1)"
    keywords = ("at_least",)

    def __post_init__(self) -> None:
        options = check_items("Selection options", self.options, Option, example="(Option.parse('tactile_pad@weiss'), ...)")
        object.__setattr__(self, "options", options)
        if not self.options:
            raise ModelError("Selection has no options: list at least one alternative, e.g. 'tactile_pad@weiss'")
        twice = [o for i, o in enumerate(self.options) if o in self.options[:i]]
        if twice:  # (it would count twice towards at_least)
            raise ModelError(f"Selection lists the option {twice[0].describe()} twice: list each alternative once")
        check_number("Selection at_least", self.at_least, integer=True)
        object.__setattr__(self, "at_least", int(self.at_least))
        if self.at_least < 1:
            raise ModelError("Selection at_least = 0 always holds: give at_least >= 1 or drop the requirement")
        both = overlapping_options(self.options) if self.at_least > 1 else None
        if both is not None:
            wider, o = both
            raise ModelError(
                f"Selection lists {wider.describe()!r} and {o.describe()!r}: one {o.describe()} device meets both, so "
                f"at_least = {self.at_least} counts it twice; to ask for several devices write "
                f"('quantity', {o.device_kind!r}, N), else drop one of the two"
            )
        if self.at_least > len(self.options):
            raise ModelError(
                f"Selection at_least = {self.at_least} but only {len(self.options)} options "
                f"({', '.join(o.describe() for o in self.options)}): lower at_least or add options"
            )

    def describe(self) -> str:
        return f"Selection({self.at_least} of {', '.join(o.describe() for o in self.options)})"

    @classmethod
    def arity(cls) -> int | None:
        return None  # options, as many as given

    @classmethod
    def from_words(cls, *args: object, **kwargs: object) -> Requirement:
        opts: Iterable[object] = args
        if len(args) == 1 and isinstance(args[0], (list, tuple)):
            opts = args[0]
        return cls(tuple(Option.parse(o) for o in opts), kwargs.get("at_least", 1))  # type: ignore[arg-type]

    def holds(self, state: "PlatformState", graph: Placing) -> str | None:
        held = [o for o in self.options if o.holds(state)]
        if len(held) >= self.at_least:
            return None
        have = [o.describe() for o in held]
        return f"{len(have)} of the options available ({', '.join(have) or 'none'}), needs {self.at_least}"

    def reads_fixed_facts(self) -> bool:
        return all(o.attribute is not None for o in self.options)

    def best_state_decides(self) -> bool:
        return True  # each option reads a fixed attribute or the working devices

    def device_only(self) -> bool:
        return all(o.attribute is None for o in self.options)

    def platform_problem(self, platforms: "tuple[Platform, ...]") -> str | None:
        for opt in self.options:
            if opt.attribute is not None:
                problem = attribute_problem(opt.attribute, opt.value, platforms)
                if problem is not None:
                    return f"option {opt.describe()!r}: {problem}"
        return None

    def device_problem(self, devices: "tuple[Device, ...]") -> str | None:
        """Why an option names a device kind or a kind@vendor no device is."""
        kinds = sorted({d.kind for d in devices})
        for opt in self.options:
            if opt.device_kind is None:
                continue
            if opt.device_kind not in kinds:
                return (
                    f"option {opt.describe()!r}: no device is of kind {opt.device_kind!r}{suggest(opt.device_kind, kinds)}: "
                    f"fix the kind (kinds: {', '.join(kinds)})"
                )
            if opt.vendor is not None:
                vendors = sorted({d.vendor for d in devices if d.kind == opt.device_kind})
                if opt.vendor not in vendors:
                    return (
                        f"option {opt.describe()!r}: no {opt.device_kind} device is made by {opt.vendor!r}"
                        f"{suggest(opt.vendor, vendors)}, so it can never hold: fix the vendor "
                        f"({opt.device_kind} vendors: {', '.join(vendors)})"
                    )
        return None

    def to_json(self) -> dict[str, Any]:
        options = [{f.name: getattr(o, f.name) for f in fields(o) if getattr(o, f.name) is not None} for o in self.options]
        return {"requirement": "selection", "options": options, "at_least": self.at_least}

    @classmethod
    def json_args(cls, args: dict[str, Any], where: str, item: Callable[[str, type, object, str], object]) -> dict[str, Any]:
        if "options" in args:
            options = args["options"]
            if not isinstance(options, list):
                raise CheckerError(f"{where}.options = {options!r} is not a list: write [{{\"device_kind\": \"tactile_pad\"}}, ...]")
            example = '{"device_kind": "tactile_pad", "vendor": "weiss"}'
            args["options"] = tuple(item(f"{where}.options[{i}]", Option, o, example) for i, o in enumerate(options))
        return args

    def column_mask(self, cols: Columns, graph: Placing) -> Any:
        return cols.how_many(self.options) >= self.at_least

    def column_keys(self, cols: Columns, rows: Any, graph: Placing) -> Any:
        return cols.option_keys(self.options, rows)  # which options hold


@dataclass(frozen=True, slots=True)
class Reads(Requirement):
    """The requirement a perception graph's inputs make: a device of ``kind`` it reads is
    readable (docs/design.md §6, the Control rules' reading rule).

    Nobody writes it: :class:`~desmon.model.system.SystemModel` derives one per device
    kind a graph's sensor components read (:attr:`DeploymentSpec.reads`). ``devices``
    are the declared devices of that kind as ``(device, platform)`` pairs, in
    declaration order. On a platform that hosts some of them the graph reads its own
    (one must work there); elsewhere it reads any of them, so one must work on a
    platform that is up. The first half is a fact of the platform alone and is checked
    with its other requirements (:meth:`holds`); the second is read from the hosting
    platforms' facts (:func:`desmon.deployment.validity.unreadable_inputs`).
    """

    #: (it reads a platform's name only to find the devices the platform hosts, which
    #: interchangeable platforms carry alike and swap with their names)
    symmetric = True
    kind: str
    devices: tuple[tuple[str, str], ...]
    #: The platforms hosting a device of this kind, in declaration order, without repeats
    #: (derived from ``devices`` once: every validity question asks it).
    hosts: tuple[str, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "hosts", tuple(dict.fromkeys(p for _d, p in self.devices)))

    def describe(self) -> str:
        return f"reads {self.kind}"

    def holds(self, state: "PlatformState", graph: Placing) -> str | None:
        """The platform's own half: on a platform hosting devices of the kind the graph
        reads those, so one of them must work there (the other half, elsewhere, is
        :func:`desmon.deployment.validity.unreadable`)."""
        name = state.platform.name
        if name not in self.hosts or any(d.kind == self.kind for d in state.devices):
            return None
        own = ", ".join(d for d, p in self.devices if p == name)
        return f"{own} on {name} failed"

    def column_mask(self, cols: Columns, graph: Placing) -> Any:
        return ~cols.hosted_by(self.hosts) | (cols.count(self.kind) > 0)

    def column_keys(self, cols: Columns, rows: Any, graph: Placing) -> Any:
        return cols.row_key(rows)  # the text names the row's platform and its devices


#: The requirement kinds of desmon itself (:func:`requirement_kinds` adds those defined later).
REQUIREMENT_KINDS = requirement_kinds()


#: the largest preference weight: a score of weights above it keeps none of its decimals
MAX_WEIGHT = 1e3

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
class Preference(Constraint):
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

    soft = True

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
        if self.weight > MAX_WEIGHT:
            raise ModelError(
                f"preference {self.kind!r} weight {self.weight:g}: over {MAX_WEIGHT:g}, a score keeps none of the 12 decimals "
                "scores are compared to (double precision holds about 16 digits) and near 1e308 it overflows, so platforms "
                "would tie by accident: scale every weight of the specification down alike"
            )

    def describe(self) -> str:
        inner = {
            "vendor": lambda a: f"{a[0]}@{a[1]}",
            "attribute": lambda a: f"{a[0]}={a[1]}",
        }.get(self.kind, lambda a: ", ".join(a))(self.args)
        return f"prefer {self.kind}({inner}) x{self.weight:g}"

    def holds(self, state: "PlatformState", graph: Placing) -> str | None:
        return None  # a preference never rejects a platform: it scores it (validity.preference_term)

    def to_json(self) -> dict[str, Any]:
        """``{"preference": KIND, "args": [...], "weight": w}``."""
        return {"preference": self.kind, "args": list(self.args), "weight": self.weight}


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


def constraint_types() -> tuple[type[Constraint], ...]:
    """What a deployment specification lists: every requirement kind users write (as
    :func:`requirement_kinds`), then :class:`Preference`."""
    return (*requirement_classes(), Preference)


def make_requirement(kind: str, *args: object, **kwargs: object) -> Requirement:
    """Build a requirement from DepSL-style words: ``make_requirement("capacity", "memory", 250)``.

    Kinds: quantity(kind, n), capacity(resource, amount), minimum(prop, v),
    maximum(prop, v), attribute(name, value), selection(option, ..., at_least=1),
    and any kind defined since (:func:`requirement_kinds`; each class's ``usage``).
    """
    words = requirement_kinds()
    if not isinstance(kind, str):
        raise ModelError(f"requirement kind {kind!r} is not a string: use one of {', '.join(words)}")
    key = kind.lower().lstrip(":")
    cls = requirement_class(key)
    if cls is None:
        raise ModelError(f"unknown requirement kind {kind!r}{suggest(key, words)}: use one of {', '.join(words)}")
    check_keywords(f"requirement {kind!r}", kwargs, cls.keywords, usage=cls.usage)
    arity = cls.arity()
    if arity is not None and len(args) != arity:
        shown = ", ".join(repr(a) for a in args) or "nothing"
        raise ModelError(f"requirement {kind!r} got {len(args)} argument(s) ({shown}) but takes {arity}: {cls.usage}")
    return cls.from_words(*args, **kwargs)


def capacity_twice(requirements: Iterable[Constraint]) -> str | None:
    """The resource two Capacity requirements of ``requirements`` name, if any: a graph
    consumes one amount of each resource, so a specification has at most one."""
    seen: set[str] = set()
    for r in requirements:
        if isinstance(r, Capacity):
            if r.resource in seen:
                return r.resource
            seen.add(r.resource)
    return None


def declared_order(requirements: Iterable[Constraint], declared: tuple[Constraint, ...]) -> tuple[Constraint, ...]:
    """``requirements`` in the one order their set has: those in ``declared`` (a graph's
    declared requirements) in their declared order, then the others by kind name and
    description (what they mean: ``Attribute("gen", 1)`` and ``Attribute("gen", "1")`` sort
    alike, as they are equal), then ``repr``. Requirements and preferences alike; the order
    changes no decision (a preference's score is a sum, rounded), only the order reasons
    are listed in."""
    have = tuple(requirements)
    first = tuple(next(h for h in have if h == r) for r in declared if r in have)  # (the objects given, in declared order)
    rest = sorted((r for r in have if r not in declared), key=lambda r: (type(r).__name__, _description(r), repr(r)))
    return first + tuple(rest)


def _description(r: Constraint) -> str:
    """``r.describe()``, or "" for a kind of the user's that describes nothing."""
    try:
        return str(r.describe())
    except Exception:
        return ""


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
            f"deployment specification of {self.graph!r} requirements", self.requirements, constraint_types(),
            example="(Capacity('memory', 150),) or add_constraint('capacity', 'memory', 150)",
        )
        object.__setattr__(self, "requirements", reqs)
        again = next((r for i, r in enumerate(reqs) if r in reqs[:i]), None)
        if again is not None:  # (as the DSL's require() refuses it: it would be checked, and explained, twice)
            raise ModelError(f"deployment specification of {self.graph!r} lists {_description(again) or repr(again)} twice: give it once")
        twice = capacity_twice(reqs)
        if twice is not None:
            raise ModelError(
                f"deployment specification of {self.graph!r} has two Capacity requirements on {twice!r}: a graph consumes "
                f"one amount of a resource (placement would check each alone, and the run charge their sum); give one "
                f"Capacity({twice!r}, TOTAL)"
            )
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
        """What a deployment of this spec consumes, per resource (its Capacity amount of each resource: one per resource)."""
        use: dict[str, float] = {}
        for req in self.requirements:
            if isinstance(req, Capacity):
                use[req.resource] = use.get(req.resource, 0.0) + req.amount
        return tuple(sorted(use.items()))
