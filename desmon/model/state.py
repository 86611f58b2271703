"""The run-time facts about one platform, as requirement checking reads them.

:class:`PlatformState` is what every requirement kind's ``holds`` reads (whoever holds
the facts: the networkx repository or the checker's state); it names only platforms and
devices, so the kinds (:mod:`desmon.model.kinds`) and the system model
(:mod:`desmon.model.system`, which re-exports it) both sit above it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from desmon.errors import ModelError
from desmon.model.platform import Device, Platform

__all__ = ["PlatformState", "new_platform_state", "with_load"]


def with_load(load: dict[str, float], resource: str, amount: float) -> dict[str, float] | None:
    """``load`` with ``resource`` set to ``amount``, or None if nothing changes.

    Canonical form shared by the repository and the checker's state store: a zero amount
    has no entry, so equal facts always look equal.
    """
    if load.get(resource, 0.0) == amount:
        return None
    out = dict(load)
    if amount:
        out[resource] = amount
    else:
        out.pop(resource, None)
    return out


@dataclass(frozen=True, slots=True)
class PlatformState:
    """Run-time facts about one platform, as requirement checking sees them.

    ``devices`` are the *working* devices attached (HAS_DEVICE edges); ``deployed``
    lists the graphs active on it with what each consumes; ``load`` is the background
    (non-monitor) consumption per resource.
    """

    platform: Platform
    up: bool = True
    devices: tuple[Device, ...] = ()
    load: tuple[tuple[str, float], ...] = ()
    deployed: tuple[tuple[str, tuple[tuple[str, float], ...]], ...] = ()
    # The hash, computed on first use (a performance cache: states are dictionary keys
    # of the validity memo; no part of equality, repr or the constructor).
    _hash: int = field(default=-1, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        # One entry per resource and per graph: a resource named twice in ``load`` would be
        # read two ways (load_of takes the first entry, the placement columns the last).
        # States are built very often, so the common cases (no or one entry) cost one len().
        # The slots are read through their descriptors: the table engine's recording
        # subclass guards the fields against reads by a reaction, and this is none.
        load = _LOAD_SLOT(self)
        if len(load) > 1 and len(dict(load)) != len(load):
            raise ModelError(_named_twice(self.platform, "load", "resource", load))
        deployed = _DEPLOYED_SLOT(self)
        if deployed:
            if len(deployed) > 1 and len(dict(deployed)) != len(deployed):
                raise ModelError(_named_twice(self.platform, "deployed", "graph", deployed))
            for graph, use in deployed:
                if len(use) > 1 and len(dict(use)) != len(use):
                    raise ModelError(_named_twice(self.platform, f"deployed consumption of {graph!r}", "resource", use))

    def __hash__(self) -> int:
        h = self._hash
        if h == -1:
            h = hash((self.platform, self.up, self.devices, self.load, self.deployed))
            object.__setattr__(self, "_hash", h)
        return h

    def __reduce__(self) -> tuple:
        # never carry the cached hash across processes (string hashes are salted)
        return (PlatformState, (self.platform, self.up, self.devices, self.load, self.deployed))

    @property
    def name(self) -> str:
        return self.platform.name

    def with_deployed(self, deployed: tuple[tuple[str, tuple[tuple[str, float], ...]], ...]) -> "PlatformState":
        """The same platform and facts with other deployments on it (what a port that shows
        the deployments otherwise -- a mutant, a what-if -- hands out)."""
        return PlatformState(self.platform, self.up, self.devices, self.load, deployed)

    def load_of(self, resource: str) -> float:
        for res, amount in self.load:
            if res == resource:
                return amount
        return 0.0

    def used_by(self, resource: str, *, excluding: str | None = None) -> list[tuple[str, float]]:
        """(graph, amount) of ``resource`` consumed by deployed graphs, optionally without one graph."""
        out = []
        for graph, use in self.deployed:
            if graph == excluding:
                continue
            for res, amount in use:
                if res == resource and amount:
                    out.append((graph, amount))
        return out


#: readers of PlatformState's slots (what a subclass that guards a field cannot intercept)
_LOAD_SLOT = PlatformState.load.__get__
_DEPLOYED_SLOT = PlatformState.deployed.__get__
#: writers of PlatformState's slots, in field order (see :func:`new_platform_state`)
_STATE_SETTERS = tuple(getattr(PlatformState, name).__set__ for name in ("platform", "up", "devices", "load", "deployed", "_hash"))


def new_platform_state(
    platform: Platform, up: bool, devices: tuple[Device, ...], load: tuple[tuple[str, float], ...],
    deployed: tuple[tuple[str, tuple[tuple[str, float], ...]], ...],
) -> PlatformState:
    """``PlatformState(platform, up, devices, load, deployed)``, every field given, built
    without the frozen class's ``__init__`` (which sets each slot through
    ``object.__setattr__``) and checked by its ``__post_init__`` all the same: a Query
    port builds one whenever a platform's facts change. Equal to the constructor's."""
    state = object.__new__(PlatformState)
    s_platform, s_up, s_devices, s_load, s_deployed, s_hash = _STATE_SETTERS
    s_platform(state, platform)
    s_up(state, up)
    s_devices(state, devices)
    s_load(state, load)
    s_deployed(state, deployed)
    s_hash(state, -1)
    state.__post_init__()
    return state


def _named_twice(platform: object, field_: str, each: str, pairs: tuple[tuple[str, object], ...]) -> str:
    """The message for a PlatformState ``field_`` that names one ``each`` twice."""
    name = getattr(platform, "name", platform)
    seen: dict[str, list[object]] = {}
    for key, value in pairs:
        seen.setdefault(key, []).append(value)
    key, values = next((k, v) for k, v in seen.items() if len(v) > 1)
    shown = " and ".join(repr(v) for v in values)
    fix = "its total" if each == "resource" else "what it consumes"
    return f"PlatformState of {name!r}: {field_} names {each} {key!r} {len(values)} times ({shown}): give each {each} once, with {fix}"
