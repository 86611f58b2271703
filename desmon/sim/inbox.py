"""What one robot's deployer process has yet to react to.

:class:`Inbox` collects what the repository's Notify subscription (or a fleet's router)
reports -- platforms changed, the context changed, specifications changed -- and wakes
the deployer driver (:mod:`desmon.sim.driver`), which takes it as a stimulus.
"""

from __future__ import annotations

from typing import Any, Iterable

import simpy

from desmon.deployment.monitor import Stimulus
from desmon.repository import labels as L
from desmon.repository.store import UPDATE_NODE, Repository

__all__ = ["Inbox"]


class Inbox:
    """What the deployer process has yet to react to, and the event that wakes it."""

    def __init__(self, repo: Repository) -> None:
        self.repo = repo
        self.platforms: dict[str, None] = {}
        self.context = False
        self.specs: dict[str, None] = {}
        self.wake: simpy.Event | None = None
        # (platforms, context, specs) -> the Stimulus taken for them (immutable, so one
        # object serves every equal take; a robot's few platforms make few keys)
        self._stimuli: dict[tuple[tuple[str, ...], bool, tuple[str, ...]], Stimulus] = {}

    def notify(self, change: Any) -> None:
        """Notify: a repository change the deployer reacts to (context, HAS_DEVICE, platform)."""
        if change.label == L.IN_CONTEXT:
            self.context = True
        elif change.label == L.HAS_DEVICE:
            self.platforms[self.repo.node_data[change.source]["name"]] = None
        elif change.label == L.PLATFORM and change.op == UPDATE_NODE:
            self.platforms[self.repo.node_data[change.node]["name"]] = None
        self._wake()

    def add(self, platforms: Iterable[str], specs: Iterable[str]) -> None:
        """A requirement change the context monitor wrote: its platforms and specifications."""
        self.platforms.update(dict.fromkeys(platforms))
        self.specs.update(dict.fromkeys(specs))
        self._wake()

    def _wake(self) -> None:
        if self.wake is not None and not self.wake.triggered:
            self.wake.succeed()

    def pending(self) -> bool:
        return bool(self.platforms or self.context or self.specs)

    def take(self) -> Stimulus:
        key = (tuple(self.platforms), self.context, tuple(self.specs))
        stim = self._stimuli.get(key)
        if stim is None:
            if len(self._stimuli) > 1024:
                self._stimuli.clear()
            stim = self._stimuli[key] = Stimulus(*key)
        self.platforms = {}
        self.context = False
        self.specs = {}
        return stim
