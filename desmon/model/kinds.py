"""The base of every requirement kind, and the registry the kinds fill themselves.

A kind is one class (docs/design.md §2, "Recipe: a new requirement kind"): a frozen,
slotted dataclass deriving from :class:`Requirement` that carries its fields and their
checks, :meth:`~Constraint.holds` (its semantics, docs/design.md §4),
:meth:`~Constraint.describe`, its DSL and JSON words, its facts problems and,
optionally, its columns for the vectorised placement. Defining the class with a
:attr:`~Requirement.word` registers it: the DSL (:func:`~desmon.model.requirements.make_requirement`),
the JSON codec (:mod:`desmon.model.codec`) and :class:`~desmon.model.requirements.DeploymentSpec`
read the kinds from :func:`requirement_kinds`. desmon's own kinds are in
:mod:`desmon.model.requirements`.
"""

from __future__ import annotations

from dataclasses import fields
from typing import TYPE_CHECKING, Any, Callable, ClassVar

from desmon.errors import ModelError
from desmon.model.checks import PLATFORM_HAS, suggest

if TYPE_CHECKING:
    from desmon.model.platform import Device, Platform
    from desmon.model.state import PlatformState

__all__ = [
    "PLATFORM_HAS", "Placing", "Columns", "Constraint", "Requirement", "requirement_kinds", "requirement_class", "requirement_classes",
    "property_problem", "attribute_problem", "device_kind_problem", "others_using",
]

# PLATFORM_HAS (desmon.model.checks, re-exported here): the Attribute name that means "the
# platform has a working device of this kind" (R1); a platform's own attributes may not take it.

#: The graph being placed, or a tuple (the graph, then graphs whose Capacity shares
#: are to be treated as freed), or None (no graph: every deployed share counts).
Placing = str | tuple[str, ...] | None

#: The column store a kind's vectorised hooks receive
#: (:class:`desmon.deployment.placement.PlatformColumns`: numpy lives there, not here).
Columns = Any

#: Every requirement kind a user can write, by its word, in definition order: filled by
#: :meth:`Requirement.__init_subclass__` (see :func:`requirement_kinds`).
_KINDS: dict[str, type["Requirement"]] = {}


class Constraint:
    """What a deployment specification lists: a hard :class:`Requirement` or a soft
    :class:`Preference`. The defaults here are those of a kind that reads run-time facts,
    names no platform fact a model must declare, and has no vector path."""

    __slots__ = ()

    #: A preference never rejects a platform (it scores it).
    soft: ClassVar[bool] = False

    def holds(self, state: "PlatformState", graph: Placing) -> str | None:
        """``None`` if this holds on ``state`` for placing ``graph``, else the reason it fails."""
        raise NotImplementedError(f"{type(self).__name__} defines no holds(state, graph)")

    def describe(self) -> str:
        raise NotImplementedError(f"{type(self).__name__} defines no describe()")

    def to_json(self) -> dict[str, Any]:
        """This constraint as the JSON of ``desmon verify --json`` (see :mod:`desmon.model.codec`)."""
        raise NotImplementedError(f"{type(self).__name__} defines no to_json()")

    def reads_fixed_facts(self) -> bool:
        """Does it read only a platform's fixed facts (properties, attributes), never its
        run-time ones (devices, load, deployments)? Its answer for a platform then never changes."""
        return False

    def device_only(self) -> bool:
        """Does only a platform's working devices decide it (the Control rules' device rule)?"""
        return False

    def best_state_decides(self) -> bool:
        """Does it hold on a platform in some state only if it holds there in the platform's
        best one (up, every device working, no load, nothing deployed)? Then a requirement no
        platform meets in its best state can never hold (the model's build refuses it)."""
        return self.reads_fixed_facts() or self.device_only()

    def platform_problem(self, platforms: "tuple[Platform, ...]") -> str | None:
        """Why it names a platform fact (capacity, property, attribute, attribute value) no
        platform declares -- it can never hold, almost surely a typo -- or None."""
        return None

    def device_problem(self, devices: "tuple[Device, ...]") -> str | None:
        """Why it names a device kind (or kind@vendor) no device is, or None (asked only of
        a model with devices)."""
        return None

    # -- the vectorised path (desmon.deployment.placement) ---------------------------------
    #: ``column_mask(cols, graph)``: the boolean row mask where it holds, computed from the
    #: primitives of ``cols`` (:class:`~desmon.deployment.placement.PlatformColumns`).
    #: None: no vector path; a requirement list holding it takes the scalar loop.
    column_mask: ClassVar[Callable[..., Any] | None] = None

    def column_keys(self, cols: Columns, rows: Any, graph: Placing) -> Any:
        """rows (x width) integers such that rows with equal keys get byte-equal reasons from
        :meth:`holds` (keys may split rows whose texts are equal, never join rows whose
        texts differ). The default, every row its own class, is always right."""
        return cols.row_key(rows)

    def column_texts(self, cols: Columns, rows: Any, graph: Placing) -> list[str] | None:
        """The reasons on the failing ``rows`` formatted from the columns, or None (ask
        :meth:`holds`, once per class of :meth:`column_keys`)."""
        return None

    def column_numbers(self) -> tuple[object, ...]:
        """The numbers :attr:`column_mask` compares (float64 must hold them exactly)."""
        return ()

    #: Do its reasons depend on the graph placed (a Capacity's, which leave out its share)?
    texts_read_graph: ClassVar[bool] = False

    #: Does the class that defines :meth:`holds` define :attr:`column_mask` too? (A
    #: subclass overriding the semantics but not the columns declines the vector path.)
    vectorised: ClassVar[bool] = False

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        owner = next(k for k in cls.__mro__ if "holds" in k.__dict__)
        cls.vectorised = owner.__dict__.get("column_mask") is not None


class Requirement(Constraint):
    """A hard requirement: a platform either meets it or is not acceptable.

    A subclass with a :attr:`word` is a kind users write (DSL, JSON); it registers
    itself when defined. Define it a frozen, slotted dataclass under
    ``@strict_init(ModelError)`` like the kinds below.
    """

    __slots__ = ()

    #: Its word in the DSL (``add_constraint(word, ...)``) and in JSON (``"requirement"``);
    #: None: not written by users (:class:`Reads`, derived by the model).
    word: ClassVar[str | None] = None
    #: How to write it in the DSL (the end of a message about a bad call).
    usage: ClassVar[str] = ""
    #: The keyword arguments :meth:`from_words` takes.
    keywords: ClassVar[tuple[str, ...]] = ()
    #: Whether its answer on a platform stays the same when interchangeable platforms and
    #: their devices swap names: it reads facts, never a name (``desmon verify
    #: --symmetry`` refuses a model with a requirement that does not say so). A kind of
    #: your own that never reads ``state.platform.name`` or a device's name may set it True.
    symmetric: ClassVar[bool] = False

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if type(cls.__dict__.get("symmetric", False)) is not bool:  # ("no" would read as yes)
            raise ModelError(f"requirement kind {cls.__name__}: symmetric = {cls.__dict__['symmetric']!r}; give True or False")
        word = cls.__dict__.get("word")
        if word is None:
            return
        old = _KINDS.get(word)
        if old is not None and (old.__module__, old.__name__) != (cls.__module__, cls.__name__):
            raise ModelError(
                f"requirement kind {word!r} is defined twice ({old.__module__}.{old.__name__} and "
                f"{cls.__module__}.{cls.__name__}): give one another word"
            )
        _KINDS[word] = cls  # @dataclass(slots=True) rebuilds the class (same name): the final one stays

    @classmethod
    def unregister(cls) -> None:
        """Forget this kind (a test or a session that defined one for a while)."""
        if cls.word is not None and _KINDS.get(cls.word) is cls:
            del _KINDS[cls.word]

    @classmethod
    def arity(cls) -> int | None:
        """How many positional DSL words it takes (None: any number): its fields by default."""
        return sum(1 for f in fields(cls) if f.init)  # type: ignore[arg-type]

    @classmethod
    def from_words(cls, *args: object, **kwargs: object) -> "Requirement":
        """Build it from DSL words (:func:`make_requirement`, :meth:`arity` of them): its fields in order."""
        return cls(*args, **kwargs)

    def to_json(self) -> dict[str, Any]:
        """``{"requirement": WORD, FIELD: value, ...}`` (its dataclass fields by name)."""
        return {"requirement": self.word, **{f.name: getattr(self, f.name) for f in fields(self)}}  # type: ignore[arg-type]

    @classmethod
    def json_args(cls, args: dict[str, Any], where: str, item: Callable[[str, type, object, str], object]) -> dict[str, Any]:
        """The constructor arguments from the JSON ``args`` (what :meth:`to_json` wrote,
        without ``"requirement"``); ``item(where, cls, data, example)`` builds a nested
        object with a one-line error. The fields as they are by default."""
        return args


def requirement_kinds() -> tuple[str, ...]:
    """The words of every requirement kind defined now, in definition order."""
    return tuple(_KINDS)


def requirement_class(word: str) -> type[Requirement] | None:
    """The requirement kind written ``word`` (None if there is none)."""
    return _KINDS.get(word)


def requirement_classes() -> tuple[type[Requirement], ...]:
    """Every requirement kind defined now, in definition order (as :func:`requirement_kinds`)."""
    return tuple(_KINDS.values())


def device_kind_problem(wanted: str, devices: "tuple[Device, ...]") -> str | None:
    """Why no device is of kind ``wanted`` (None if one is)."""
    kinds = sorted({d.kind for d in devices})
    if wanted in kinds:
        return None
    return f"no device is of kind {wanted!r}{suggest(wanted, kinds)}: fix the kind (kinds: {', '.join(kinds)})"


def attribute_problem(name: str, value: object, platforms: "tuple[Platform, ...]") -> str | None:
    """Why no platform has attribute ``name`` equal to ``value`` as text (None if one does)."""
    declared = sorted({k for p in platforms for k, _ in p.attributes})
    if name not in declared:
        if any(k == name for p in platforms for k, _ in p.properties):
            return f"{name!r} is a number the platforms declare as a property, not an attribute: write ('minimum', {name!r}, value) or ('maximum', {name!r}, value)"
        return (
            f"no platform declares an attribute {name!r}{suggest(name, declared)}: "
            f"add attributes={{{name!r}: ...}} to the platforms or fix the name (attributes: {', '.join(declared) or 'none'})"
        )
    # attributes compare as text (holds); a value no platform has never holds
    values = sorted({str(v) for p in platforms for k, v in p.attributes if k == name})
    if str(value) not in values:
        return (
            f"no platform has {name} = {value!r}{suggest(str(value), values)}: fix the value "
            f"(values of {name!r}: {', '.join(repr(v) for v in values)})"
        )
    return None


def property_problem(prop: str, platforms: "tuple[Platform, ...]") -> str | None:
    """Why no platform declares the numeric property ``prop`` (None if one does): the facts
    problem of a kind reading a property (Minimum, Maximum)."""
    declared = sorted({k for p in platforms for k, _ in p.properties})
    if prop in declared:
        return None
    if any(k == prop for p in platforms for k, _ in p.capacities):
        return f"{prop!r} is a capacity the deployments consume, not a property: write ('capacity', {prop!r}, amount) for what the graph needs free"
    return (
        f"no platform declares a property {prop!r}{suggest(prop, declared)}: "
        f"add properties={{{prop!r}: ...}} to the platforms or fix the name (properties: {', '.join(declared) or 'none'})"
    )


def others_using(resource: str, state: "PlatformState", graph: Placing) -> list[tuple[str, float]]:
    """Shares of ``resource`` held by graphs other than the one being placed (and, for a
    tuple ``graph``, other than the graphs a placement would free)."""
    if graph is None or type(graph) is str:
        return state.used_by(resource, excluding=graph)  # type: ignore[arg-type]
    return [(g, a) for g, a in state.used_by(resource) if g not in graph]
