"""The context monitor's interpretation: observations and events -> repository facts.

Pure logic over an :class:`InsertPort` (implemented by the networkx repository adapter
and by the checker's state store; the events write through it, so it is
:mod:`desmon.model.events`' and re-exported here): it decides *what* to write and
reports what changed as a :class:`Stimulus`, which is what wakes the selector and the
deployer (Notify).
"""

from __future__ import annotations

from dataclasses import dataclass

from desmon.deployment.memo import MemoChecks
from desmon.errors import ModelError
from desmon.model.actions import GRASP, HOLD, IDLE, MOVE_BASE, RELEASE
from desmon.model.events import Effects, Event, InsertPort

__all__ = ["GripperObservation", "interpret", "InsertPort", "Stimulus", "Stimuli", "observe"]

GRIPPER_STATES = ("open", "closing", "closed", "opening")


@dataclass(frozen=True, slots=True)
class GripperObservation:
    """What the context monitor sees of gripper and base."""

    gripper: str
    base_moving: bool = False
    holding: bool = True

    def __post_init__(self) -> None:
        if self.gripper not in GRIPPER_STATES:
            raise ModelError(f"gripper state {self.gripper!r} unknown: use one of {', '.join(GRIPPER_STATES)}")


def interpret(obs: GripperObservation) -> str:
    """Action context from gripper and base (the paper's §4.1).

    Fingers closing -> grasp; fingers opening -> release; fingers closed on an object
    with the base moving -> move_base, base still -> hold; otherwise idle.
    """
    if obs.gripper == "closing":
        return GRASP
    if obs.gripper == "opening":
        return RELEASE
    if obs.gripper == "closed" and obs.holding:
        return MOVE_BASE if obs.base_moving else HOLD
    return IDLE


@dataclass(frozen=True, slots=True)
class Stimulus:
    """What a repository change means for the deployment core (the Notify payload)."""

    changed_platforms: tuple[str, ...] = ()
    context_changed: bool = False
    #: graphs whose deployment requirements changed (their platforms are in
    #: ``changed_platforms``, so Algorithm 2 re-checks the deployments there)
    specs_changed: tuple[str, ...] = ()

    @property
    def empty(self) -> bool:
        return not self.changed_platforms and not self.context_changed and not self.specs_changed


#: The stimuli that need no memo: nothing changed, the context changed.
_NOTHING = Stimulus()
_CONTEXT_CHANGED = Stimulus(context_changed=True)


def _one_platform(platform: str) -> Stimulus:
    return Stimulus(changed_platforms=(platform,))


class Stimuli(Effects):
    """The stimuli an event's :meth:`~desmon.model.events.Event.write` returns. With a
    run's ``memo`` (:class:`~desmon.deployment.memo.MemoChecks`, the core's) the stimulus
    of one changed platform is interned there (one object per platform); without, each
    is made afresh (equal either way: they are immutable)."""

    nothing = _NOTHING
    context_changed = _CONTEXT_CHANGED

    def __init__(self, memo: MemoChecks | None = None) -> None:
        self._known = memo.values("stimulus") if memo is not None else None

    def platform_changed(self, platform: str) -> Stimulus:
        known = self._known
        if known is None:
            return _one_platform(platform)
        stim = known.get(platform)
        if stim is None:
            stim = known.keep(platform, _one_platform(platform))
        return stim  # type: ignore[no-any-return]

    def specs_changed(self, hosts: tuple[str, ...], graph: str) -> Stimulus:
        return Stimulus(changed_platforms=hosts, specs_changed=(graph,))

    def merged(self, first: Stimulus, second: Stimulus) -> Stimulus:
        """One stimulus for both (:class:`~desmon.model.events.Together`): the platforms and
        specifications of either, in order, and a context change if either has one."""
        if second.empty:
            return first
        if first.empty:
            return second
        return Stimulus(
            tuple(dict.fromkeys((*first.changed_platforms, *second.changed_platforms))),
            first.context_changed or second.context_changed,
            tuple(dict.fromkeys((*first.specs_changed, *second.specs_changed))),
        )


_PLAIN = Stimuli()


def observe(event: Event, store: InsertPort, stimuli: Stimuli | None = None) -> Stimulus:
    """Write the facts ``event`` implies and say what changed (each kind writes its own:
    :meth:`Event.write <desmon.model.events.Event.write>`); ``stimuli`` build the answer
    (the core passes its own, which intern)."""
    if not isinstance(event, Event):
        raise ModelError(f"not an environment event: {event!r}")
    return event.write(store, stimuli if stimuli is not None else _PLAIN)  # type: ignore[no-any-return]
