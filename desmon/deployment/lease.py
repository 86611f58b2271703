"""Which on-demand platform to lease: a pure decision over the Query port.

When the deployer finds no acceptable platform for a wanted graph, the infrastructure
may lease on-demand capacity (an edge or cloud server, ``Platform(on_demand=True)``).
:func:`lease_choice` answers which absent on-demand platform would be acceptable for
the graph once it has joined, best first by the same order the deployer uses
(preferences, then platform preference, then declaration order). The SimPy world calls
it and schedules a :class:`~desmon.model.events.PlatformJoin` after the platform's
``startup_s``; the checker needs no lease policy, since joins and leaves are environment
events it explores in every order.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Iterable

from desmon.deployment.ports import QueryPort
from desmon.deployment.validity import spec_validity

__all__ = ["lease_choice"]


def lease_choice(q: QueryPort, graph: str, absent: Iterable[str]) -> str | None:
    """The best of the ``absent`` on-demand platforms on which ``graph`` would be
    acceptable if it joined now, or None (no such platform, or no specification)."""
    spec = q.deployment_information(graph)
    if spec is None:
        return None
    wanted = set(absent)
    fixed = q.fixed_platform(spec)
    world = tuple(replace(s, up=True) if s.name in wanted and s.platform.on_demand else s for s in q.platform_states())
    joined = tuple(s for s in world if s.name in wanted and s.platform.on_demand and (fixed is None or s.name == fixed))
    if not joined:
        return None
    # what the deployer would ask once it joined (validity_for): the requirements and the graph's
    # inputs, read where they are (a server never leased for a graph whose input no platform gives)
    acceptable = spec_validity(q.constraints(spec), spec.reads, joined, world, graph, reasons=False, checks=q.checks).acceptable
    return acceptable[0] if acceptable else None
