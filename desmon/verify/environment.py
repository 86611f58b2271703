"""The checker's environment: its event alphabet, one definition per kind of variable.

A transition starts with one environment event, chosen among those the scenario's
:class:`~desmon.verify.bounds.Bounds` enable in the current state; the system's
reaction follows. The environment is a list of bounded *variables* (:func:`variables`:
the context, each bounded device, platform, load and on-demand platform, each
requirement change), and every kind of variable is one :class:`VariableKind` carrying
everything the checker's parts need of it:

* its event classes (:attr:`VariableKind.events`: the report counts per kind, in
  :func:`event_kinds` order) and the events it enables in a state
  (:meth:`VariableKind.enabled`: the direct engine, through :func:`enabled_events`);
* the part of the state it moves and its array operation for the table engine
  (:meth:`VariableKind.digits` and :meth:`VariableKind.moves`: per value of that
  digit, the value after the event and the event, which
  :class:`desmon.verify.table.encoding.Events` turns into numpy operations);
* its symmetry rule (:attr:`VariableKind.symmetric`, :meth:`VariableKind.rename`:
  :mod:`desmon.verify.symmetry`);
* every event of one variable whatever the state (:meth:`VariableKind.every_event`:
  the raw events :func:`desmon.verify.strategies.events` draws from);
* the event that moves one variable to a value (:meth:`VariableKind.event_to`: the
  events of ``desmon analyze``'s timed world, :mod:`desmon.analyze.chain`);
* what gives its events a rate in ``desmon analyze`` (:attr:`VariableKind.rate`:
  :mod:`desmon.analyze.markov` refuses a variable without one) and, for a kind the
  chain does not time with a part of its own (:attr:`VariableKind.timed_by_chain`),
  the rates themselves (:meth:`VariableKind.rates`).

Defining a subclass that sets ``name`` registers the kind (after the built-in ones, in
definition order); its subjects are the bounds' ``variables[name]`` unless it reads
them from a field of its own. Every engine walks :func:`variables` in that order, so
the alphabet and its order are written once, here. docs/design.md ("Recipe: a new event
kind") says how to add one.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, ClassVar, NamedTuple, Sequence

from desmon.model.events import (
    ActionChange,
    DeviceFail,
    DeviceRepair,
    Event,
    LoadChange,
    PlatformDown,
    PlatformJoin,
    PlatformLeave,
    PlatformUp,
    RequirementChange,
    Together,
)
from desmon.verify.state import Key

__all__ = [
    "Digit", "Move", "Variable", "VariableKind", "variable_kinds", "variable_kind", "alphabet", "event_kinds",
    "variables", "failures", "can_fail", "enabled_events", "FACTS", "Moved", "moved", "contexts", "variants",
]

#: kind name -> its definition, filled by :meth:`VariableKind.__init_subclass__` (in definition order)
_KINDS: dict[str, "VariableKind"] = {}


class Digit(NamedTuple):
    """A part of the state a variable moves, as the table engine encodes it: ``fact`` is
    "context", "requirements" (``subject``: a graph: which of its requirement variants
    holds), "down" (``subject``: a platform down, or absent if on demand), "device" (a
    device failed) or "load" (a platform's load of the bounds' ``load_resource``, over
    ``levels``)."""

    fact: str
    subject: Any = None
    levels: tuple[float, ...] = ()


@dataclass(frozen=True)
class Move:
    """One array operation of the table engine: for each value of ``digit`` (numbered as
    the encoding numbers them: :meth:`VariableKind.moves`), the value after the event (-1:
    no event there), the event, and whether it needs room under ``max_failures``."""

    digit: Digit
    to: tuple[int, ...]
    events: tuple[Event | None, ...]
    needs_room: tuple[bool, ...]


@dataclass(frozen=True, slots=True)
class Variable:
    """One bounded variable of the environment: its kind's name and its ``subject`` (the
    device's or platform's name, the :class:`RequirementChange`, None for the context)."""

    kind: str
    subject: Any = None


class VariableKind:
    """The definition of one kind of checker variable (see the module docstring).

    A subclass sets ``name`` (which registers it), ``events`` and, where they apply,
    ``symmetric`` and ``rate``; it implements :meth:`enabled` and :meth:`every_event`,
    :meth:`digits` and :meth:`moves` for the table engine (without them the table engine
    refuses the search and ``--engine auto`` runs the direct engine), and :meth:`rates`
    if it has a ``rate``.
    """

    #: the kind's name (the key of ``Bounds.variables`` for a kind without a field of its own)
    name: ClassVar[str] = ""
    #: its event classes, in the order the report counts them
    events: ClassVar[tuple[type[Event], ...]] = ()
    #: whether the symmetry reduction covers it (its events then map by :meth:`rename`)
    symmetric: ClassVar[bool] = False
    #: what gives its events a rate in ``desmon analyze`` (None: nothing, analyze refuses it)
    rate: ClassVar[str | None] = None
    #: whether ``desmon analyze``'s chain times its events with a part of its own (the
    #: built-in kinds: the task cycle, faults and the monitor's heartbeat, load walks, the
    #: lease, random changes); the chain times any other kind by its :meth:`rates`
    timed_by_chain: ClassVar[bool] = False

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if cls.__dict__.get("name"):
            _KINDS[cls.name] = cls()

    @classmethod
    def unregister(cls) -> None:
        """Forget this kind (a kind defined for a test only)."""
        if type(_KINDS.get(cls.name)) is cls:
            del _KINDS[cls.name]

    def subjects(self, b: Any) -> tuple[Any, ...]:
        """Its variables' subjects under bounds ``b``, in exploration order."""
        return tuple(b.variables.get(self.name, ()))

    def problem(self, subjects: tuple[Any, ...], scenario: Any) -> str | None:
        """What is wrong with ``subjects`` (given in ``Bounds.variables``) for ``scenario``, or None."""
        return None

    def enabled(self, b: Any, key: Key, subject: Any, room: bool) -> list[Event]:
        """The events of the variable of ``subject`` enabled in ``key`` (``room``: another
        failure fits under ``max_failures``)."""
        raise NotImplementedError

    def every_event(self, b: Any, subject: Any) -> tuple[Event, ...]:
        """Every event of the variable of ``subject``, whatever the state (the raw events
        :func:`desmon.verify.strategies.events` draws from)."""
        raise NotImplementedError(f"kind of variable {self.name!r} lists no events of a variable (VariableKind.every_event)")

    def event_to(self, b: Any, subject: Any, value: Any) -> Event:
        """The event that moves the variable of ``subject`` to ``value``, a value of its
        digit as :meth:`moves` numbers them (an action for the context, True for a device
        failed, a platform down or an on-demand platform absent, a load level; a
        requirement change is its own event whatever the value)."""
        raise NotImplementedError(f"kind of variable {self.name!r} names no event for a value (VariableKind.event_to)")

    def rates(self, world: Any, b: Any, subject: Any) -> tuple[tuple[Event, float], ...]:
        """For ``desmon analyze``, a kind with a ``rate`` that the chain does not time
        itself (:attr:`timed_by_chain` False): each event of the variable of ``subject``
        with its rate per second in ``world`` (the scenario's
        :class:`desmon.sim.world.World`). The chain lets each happen at its rate whenever
        the state enables it (:meth:`enabled`); the world and the repository both see it
        at once."""
        raise NotImplementedError(f"kind of variable {self.name!r} gives its events no rates (VariableKind.rates)")

    def digits(self, b: Any, subject: Any) -> tuple[Digit, ...] | None:
        """The parts of the state its events move (None: no array operations)."""
        return None

    def moves(self, b: Any, subject: Any, values: Callable[[Digit], Sequence[Any]]) -> list[Move]:
        """Its array operations, in event order; ``values(digit)`` lists the values of a
        digit as the encoding numbers them (False/True for "down" and "device")."""
        raise NotImplementedError

    def rename(self, event: Event, platform: Callable[[str], str], device: Callable[[str], str]) -> Event:
        """``event`` under a renaming of platforms and of their devices (symmetry)."""
        return event


def variable_kinds() -> tuple[VariableKind, ...]:
    """Every registered kind of variable, in definition order."""
    return tuple(_KINDS.values())


def variable_kind(name: str) -> VariableKind | None:
    """The kind of variable called ``name``, or None."""
    return _KINDS.get(name)


def alphabet() -> tuple[type[Event], ...]:
    """The event classes the checker explores, in exploration (and report) order."""
    return tuple(cls for kind in _KINDS.values() for cls in kind.events)


def event_kinds() -> tuple[str, ...]:
    """Their kinds (:attr:`desmon.model.events.Event.kind`), in report order."""
    return tuple(cls.kind for cls in alphabet())


def variables(b: Any) -> tuple[Variable, ...]:
    """The environment's variables in exploration order: each kind's subjects, kind by
    kind (the context, the bounded devices, the platforms that may go down, the loaded
    platforms, the on-demand platforms, the requirement changes, then the registered
    kinds). :func:`enabled_events` and the table engine's event encoding
    (:class:`desmon.verify.table.encoding.Events`) both walk this list."""
    return tuple(Variable(kind.name, s) for kind in _KINDS.values() for s in kind.subjects(b))


#: the facts of a state a :class:`Digit` may name
FACTS = ("context", "requirements", "down", "device", "load")


class Moved(NamedTuple):
    """What the bounded variables move of the platforms (:func:`moved`)."""

    downs: frozenset[str]  # the platforms that may go down (or be absent)
    devices: dict[str, list[str]]  # each platform's devices that may fail, in variable order
    levels: dict[str, tuple[float, ...]]  # each loaded platform's levels, as the first variable moving it gives them
    clash: str  # a platform whose load two variables move over different levels; the reading stops there ("" if none)
    unknown: str  # the kind of a variable whose digits are not known, or name another fact or a device the model lacks; the reading stops there ("" if none)


def moved(b: Any, model: Any) -> Moved:
    """What the variables of ``b`` move of ``model``'s platforms, read off their
    :meth:`VariableKind.digits`: one reading for the table engine's encoding and the
    symmetry reduction's conditions."""
    platform_of = {d.name: d.platform for d in model.devices}
    downs: set[str] = set()
    devices: dict[str, list[str]] = {p.name: [] for p in model.platforms}
    levels: dict[str, tuple[float, ...]] = {}
    for v in variables(b):
        digits = _KINDS[v.kind].digits(b, v.subject)
        if digits is None or any(d.fact not in FACTS or (d.fact == "device" and d.subject not in platform_of) for d in digits):
            return Moved(frozenset(downs), devices, levels, "", v.kind)
        for d in digits:
            if d.fact == "down":
                downs.add(d.subject)
            elif d.fact == "device" and d.subject not in devices[platform_of[d.subject]]:
                devices[platform_of[d.subject]].append(d.subject)
            elif d.fact == "load" and levels.setdefault(d.subject, d.levels) != d.levels:
                return Moved(frozenset(downs), devices, levels, d.subject, "")
    return Moved(frozenset(downs), devices, levels, "", "")


def contexts(b: Any, init: Key) -> list[str | None]:
    """The contexts a search from ``init`` can reach under ``b``, in the order the table
    engine numbers them: the initial one, then the bounds' actions and the task's."""
    ctxs: list[str | None] = [init.context]
    for a in (*b.actions, *(b.task or {}), *(x for nxt in (b.task or {}).values() for x in nxt)):
        if a not in ctxs:
            ctxs.append(a)
    return ctxs


def variants(model: Any, changes: Sequence[RequirementChange], init: Key, limit: int) -> tuple[dict[str, list[tuple]], str]:
    """The requirements each graph that ``changes`` or ``init`` changes can have: the
    declared ones first, then the initial state's (the scenario's initial facts may change
    them), then every variant the changes reach from those (in order of discovery); and
    the first graph found with more than ``limit`` of them, where the reading stops ("" if none)."""
    out: dict[str, list[tuple]] = {}
    initial = dict(init.specs)
    for spec in model.specs:
        mine = [c for c in changes if c.graph == spec.graph]
        if not mine and spec.graph not in initial:
            continue
        found, i = [spec.requirements], 0
        if initial.get(spec.graph, spec.requirements) not in found:
            found.append(initial[spec.graph])
        while i < len(found):
            for c in mine:
                nxt = c.apply(found[i], spec.requirements)
                if nxt not in found:
                    found.append(nxt)
                    if len(found) > limit:
                        return out, spec.graph
            i += 1
        out[spec.graph] = found
    return out, ""


def failures(b: Any, key: Key) -> int:
    """The failures standing in ``key``: failed devices and platforms down (absent
    on-demand platforms are not failures)."""
    down = len(key.down) - sum(1 for p in b.joins if p in key.down) if b.joins else len(key.down)
    return len(key.failed) + down


def can_fail(b: Any, key: Key) -> bool:
    """Whether ``key`` has room for another failure under ``b.max_failures``."""
    return b.max_failures is None or failures(b, key) < b.max_failures


def enabled_events(b: Any, key: Key) -> list[Event]:
    """Every environment event ``b`` enables in state ``key``, in exploration order
    (:func:`variables`)."""
    room = can_fail(b, key)
    out: list[Event] = []
    for v in variables(b):
        out += _KINDS[v.kind].enabled(b, key, v.subject, room)
    return out


def _toggle(digit: Digit, on: Event, off: Event, *, back: bool, room: bool) -> Move:
    """A two-valued digit: ``on`` sets it (needs room when ``room``), ``off`` clears it (when ``back``)."""
    return Move(digit, (1, 0 if back else -1), (on, off), (room, False))


# -- the built-in kinds ---------------------------------------------------------------------------
class ActionVariable(VariableKind):
    """The robot's context: it moves among the bounds' actions (or along its task)."""

    name = "action"
    events = (ActionChange,)
    symmetric = True
    rate = "the World's task steps (each step's duration)"
    timed_by_chain = True

    def subjects(self, b: Any) -> tuple[Any, ...]:
        return (None,)

    def every_event(self, b: Any, subject: Any) -> tuple[Event, ...]:
        return tuple(ActionChange(a) for a in tuple(b.actions) or tuple(b.task or ()))

    def event_to(self, b: Any, subject: Any, value: str) -> Event:
        return ActionChange(value)

    def enabled(self, b: Any, key: Key, subject: Any, room: bool) -> list[Event]:
        return [ActionChange(a) for a in b.action_moves(key.context)]

    def digits(self, b: Any, subject: Any) -> tuple[Digit, ...]:
        return (Digit("context"),)

    def moves(self, b: Any, subject: Any, values: Callable[[Digit], Sequence[Any]]) -> list[Move]:
        ctxs = list(values(Digit("context")))
        nxt = [b.action_moves(c) for c in ctxs]
        return [
            Move(Digit("context"), tuple(ctxs.index(m[k]) if k < len(m) else -1 for m in nxt),
                 tuple(ActionChange(m[k]) if k < len(m) else None for m in nxt), (False,) * len(ctxs))
            for k in range(max((len(m) for m in nxt), default=0))
        ]


class DeviceVariable(VariableKind):
    """A device that may fail (within ``max_failures``) and, with ``repair``, be repaired."""

    name = "device"
    events = (DeviceFail, DeviceRepair)
    symmetric = True
    rate = "World.stochastic_faults (the device's MTTF and MTTR)"
    timed_by_chain = True

    def subjects(self, b: Any) -> tuple[Any, ...]:
        return tuple(b.devices)

    def every_event(self, b: Any, d: str) -> tuple[Event, ...]:
        return (DeviceFail(d), DeviceRepair(d))

    def event_to(self, b: Any, d: str, failed: bool) -> Event:
        return DeviceFail(d) if failed else DeviceRepair(d)

    def enabled(self, b: Any, key: Key, d: str, room: bool) -> list[Event]:
        if d in key.failed:
            return [DeviceRepair(d)] if b.repair else []
        return [DeviceFail(d)] if room else []

    def digits(self, b: Any, d: str) -> tuple[Digit, ...]:
        return (Digit("device", d),)

    def moves(self, b: Any, d: str, values: Callable[[Digit], Sequence[Any]]) -> list[Move]:
        return [_toggle(Digit("device", d), DeviceFail(d), DeviceRepair(d), back=b.repair, room=True)]

    def rename(self, event: Event, platform: Callable[[str], str], device: Callable[[str], str]) -> Event:
        return type(event)(device(event.device))  # type: ignore[attr-defined, call-arg]


class PlatformVariable(VariableKind):
    """A platform that may go down (within ``max_failures``) and, with ``repair``, come up."""

    name = "platform"
    events = (PlatformDown, PlatformUp)
    symmetric = True
    rate = "World.stochastic_faults (the platform's MTTF and MTTR)"
    timed_by_chain = True

    def subjects(self, b: Any) -> tuple[Any, ...]:
        return tuple(b.platforms)

    def every_event(self, b: Any, p: str) -> tuple[Event, ...]:
        return (PlatformDown(p), PlatformUp(p))

    def event_to(self, b: Any, p: str, down: bool) -> Event:
        return PlatformDown(p) if down else PlatformUp(p)

    def enabled(self, b: Any, key: Key, p: str, room: bool) -> list[Event]:
        if p in key.down:
            return [PlatformUp(p)] if b.repair else []
        return [PlatformDown(p)] if room else []

    def digits(self, b: Any, p: str) -> tuple[Digit, ...]:
        return (Digit("down", p),)

    def moves(self, b: Any, p: str, values: Callable[[Digit], Sequence[Any]]) -> list[Move]:
        return [_toggle(Digit("down", p), PlatformDown(p), PlatformUp(p), back=b.repair, room=True)]

    def rename(self, event: Event, platform: Callable[[str], str], device: Callable[[str], str]) -> Event:
        return type(event)(platform(event.platform))  # type: ignore[attr-defined, call-arg]


class LoadVariable(VariableKind):
    """A platform's background load, stepping to a neighbouring level of the bounds' ``loads``."""

    name = "load"
    events = (LoadChange,)
    symmetric = True
    rate = "World.load_steps (the walk's mean interval)"
    timed_by_chain = True

    def subjects(self, b: Any) -> tuple[Any, ...]:
        return tuple(b.loads)

    def every_event(self, b: Any, p: str) -> tuple[Event, ...]:
        return tuple(LoadChange(p, a, b.load_resource) for a in b.loads[p])

    def event_to(self, b: Any, p: str, level: float) -> Event:
        return LoadChange(p, level, b.load_resource)

    def enabled(self, b: Any, key: Key, p: str, room: bool) -> list[Event]:
        lv = b.loads[p]
        i = lv.index(dict(dict(key.loads).get(p, ())).get(b.load_resource, 0))
        out: list[Event] = []
        if i + 1 < len(lv):
            out.append(LoadChange(p, lv[i + 1], b.load_resource))
        if i > 0:
            out.append(LoadChange(p, lv[i - 1], b.load_resource))
        return out

    def digits(self, b: Any, p: str) -> tuple[Digit, ...]:
        return (Digit("load", p, tuple(b.loads[p])),)

    def moves(self, b: Any, p: str, values: Callable[[Digit], Sequence[Any]]) -> list[Move]:
        (digit,) = self.digits(b, p)
        lv, n = digit.levels, len(digit.levels)
        return [
            Move(digit, tuple(i + step if 0 <= i + step < n else -1 for i in range(n)),
                 tuple(LoadChange(p, lv[i + step], b.load_resource) if 0 <= i + step < n else None for i in range(n)), (False,) * n)
            for step in (+1, -1)
        ]

    def rename(self, event: Event, platform: Callable[[str], str], device: Callable[[str], str]) -> Event:
        assert isinstance(event, LoadChange)
        return LoadChange(platform(event.platform), event.amount, event.resource)


class JoinVariable(VariableKind):
    """An on-demand platform that joins while absent and leaves while present (no failure)."""

    name = "join"
    events = (PlatformJoin, PlatformLeave)
    rate = "World.lease (the platform's startup_s, and idle_s while it hosts nothing)"
    timed_by_chain = True

    def subjects(self, b: Any) -> tuple[Any, ...]:
        return tuple(b.joins)

    def every_event(self, b: Any, p: str) -> tuple[Event, ...]:
        return (PlatformJoin(p), PlatformLeave(p))

    def event_to(self, b: Any, p: str, absent: bool) -> Event:
        return PlatformLeave(p) if absent else PlatformJoin(p)

    def enabled(self, b: Any, key: Key, p: str, room: bool) -> list[Event]:
        return [PlatformJoin(p) if p in key.down else PlatformLeave(p)]

    def digits(self, b: Any, p: str) -> tuple[Digit, ...]:
        return (Digit("down", p),)

    def moves(self, b: Any, p: str, values: Callable[[Digit], Sequence[Any]]) -> list[Move]:
        return [_toggle(Digit("down", p), PlatformLeave(p), PlatformJoin(p), back=True, room=False)]


class RequirementsVariable(VariableKind):
    """A requirement change the environment may apply at any time (one that changes nothing is a no-op)."""

    name = "requirements"
    events = (RequirementChange,)
    rate = "World.random_changes (their mean interval)"
    timed_by_chain = True

    def subjects(self, b: Any) -> tuple[Any, ...]:
        return tuple(b.requirement_changes)

    def every_event(self, b: Any, change: RequirementChange) -> tuple[Event, ...]:
        return (change,)

    def event_to(self, b: Any, change: RequirementChange, value: Any) -> Event:
        return change

    def enabled(self, b: Any, key: Key, change: RequirementChange, room: bool) -> list[Event]:
        return [change]

    def digits(self, b: Any, change: RequirementChange) -> tuple[Digit, ...]:
        return (Digit("requirements", change.graph),)

    def moves(self, b: Any, change: RequirementChange, values: Callable[[Digit], Sequence[Any]]) -> list[Move]:
        vs = list(values(Digit("requirements", change.graph)))
        declared = vs[0]  # (the declared requirements are the first variant: table.encoding)
        return [Move(Digit("requirements", change.graph), tuple(vs.index(change.apply(r, declared)) for r in vs), (change,) * len(vs), (False,) * len(vs))]


class TogetherVariable(VariableKind):
    """Two changes one reaction answers (``Bounds(together=True)``): a subject is a pair of
    the other variables, in :func:`variables` order, and its events every pair of their
    events enabled together whose result stays within ``max_failures``. The
    world's deployer takes what came since its last reaction at once, in the order it
    came; the checker writes a pair in both orders where the deployer can tell them apart
    (:func:`_orders`). No array operations (the table
    engine leaves it to the direct engine), no symmetry rule, no rate (``desmon analyze``
    times one change at a time)."""

    name = "together"
    events = (Together,)

    def subjects(self, b: Any) -> tuple[Any, ...]:
        if not getattr(b, "together", False):
            return ()
        single = [Variable(k.name, s) for k in _KINDS.values() if k is not self for s in k.subjects(b)]
        return tuple((v, w) for i, v in enumerate(single) for w in single[i + 1:])

    def every_event(self, b: Any, pair: tuple[Variable, Variable]) -> tuple[Event, ...]:
        v, w = pair
        return tuple(t for e in _KINDS[v.kind].every_event(b, v.subject) for f in _KINDS[w.kind].every_event(b, w.subject) for t in _orders(e, f))

    def enabled(self, b: Any, key: Key, pair: tuple[Variable, Variable], room: bool) -> list[Event]:
        """Each pair of the two variables' events whose result stays within ``max_failures``:
        the two changes come at one instant, so a repair frees the room a failure beside
        it takes (``room``, the state's own, does not bound a pair); in both orders where
        the order reaches the deployer (:func:`_orders`)."""
        v, w = pair
        limit = b.max_failures
        standing = failures(b, key) if limit is not None else 0
        return [
            t
            for e in _KINDS[v.kind].enabled(b, key, v.subject, True)
            for f in _KINDS[w.kind].enabled(b, key, w.subject, True)
            if limit is None or standing + _failure_delta(e) + _failure_delta(f) <= limit
            for t in _orders(e, f)
        ]


def _orders(e: Event, f: Event) -> tuple[Together, ...]:
    """The pair of ``e`` and ``f`` in each order the deployer can tell apart: both, where
    each may name changed platforms (the order of the stimulus's platforms is the order
    they came, which the world's deployer reads); one, where one is the context's (a
    context change is a flag, not a position)."""
    if isinstance(e, ActionChange) or isinstance(f, ActionChange):
        return (Together(e, f),)
    return (Together(e, f), Together(f, e))


def _failure_delta(event: Event) -> int:
    """How ``event`` changes the failures under ``max_failures``: +1 for a device failing or
    a platform going down, -1 for a repair (on-demand platforms joining and leaving are no
    failures), else 0."""
    if isinstance(event, (DeviceFail, PlatformDown)):
        return 1
    if isinstance(event, (DeviceRepair, PlatformUp)):
        return -1
    return 0
