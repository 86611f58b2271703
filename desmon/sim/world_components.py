"""The names a World gives (MTTFs, load walks and steps, start latencies, the start
failure script) checked against the scenario's model, and the load each platform has at
the start: one value, whoever gives it.

Apart from :mod:`desmon.sim.world` (which calls :func:`check_components` from
``World.check_against``) so that the World's own module stays within its size."""

from __future__ import annotations

from typing import Any

from desmon.errors import ScenarioError
from desmon.model.checks import suggest
from desmon.model.events import LoadChange, Together
from desmon.model.scenario import Scenario, event_problem

__all__ = ["check_components", "check_initial_loads", "refuse_together"]


def check_components(world: Any, scenario: Scenario, where: str) -> None:
    """The devices, platforms and graphs named by MTTFs, load walks, start latencies and
    the start failure script exist in the scenario's model."""
    model = scenario.model
    devices = [d.name for d in model.devices]
    platforms = [p.name for p in model.platforms]
    for m in world.stochastic_faults:
        if m.component not in devices and m.component not in platforms:
            raise ScenarioError(
                f"{where}: MTTF for unknown component {m.component!r}{suggest(m.component, devices + platforms)} "
                f"(devices {sorted(devices)}, platforms {sorted(platforms)})"
            )
        if m.component in platforms and model.platform(m.component).on_demand:
            raise ScenarioError(f"{where}: MTTF for on-demand platform {m.component!r}: it joins and leaves; script PlatformJoin / PlatformLeave in changes= instead")
        if m.component in devices and m.component in platforms:
            raise ScenarioError(
                f"{where}: MTTF for {m.component!r} is ambiguous: it names both a device and a platform; rename one of them"
            )
    for w in world.load_walks:
        problem = event_problem(LoadChange(w.platform, w.low, w.resource), model)
        if problem is not None:
            raise ScenarioError(f"{where}: load walk: {problem}")
    for st in world.load_steps:
        problem = event_problem(LoadChange(st.platform, st.start, st.resource), model)
        if problem is not None:
            raise ScenarioError(f"{where}: load steps: {problem}")
    for p, _v in world.platform_latency:
        if p not in platforms:
            raise ScenarioError(f"{where}: start latency for unknown platform {p!r}{suggest(p, platforms)} (platforms: {', '.join(platforms)})")
    _check_start_script(world, where, [g.name for g in model.graphs], platforms)

def _check_start_script(world: Any, where: str, graphs: list[str], platforms: list[str]) -> None:
    """Each (graph, platform, n) of the start failure script names a known graph and platform."""
    for graph, platform, n in world.start_failure.script:
        if graph not in graphs:
            raise ScenarioError(
                f"{where}: start failure script ({graph!r}, {platform!r}, {n}) names unknown perception graph "
                f"{graph!r}{suggest(graph, graphs)} (graphs: {', '.join(graphs)})"
            )
        if platform not in platforms:
            raise ScenarioError(
                f"{where}: start failure script ({graph!r}, {platform!r}, {n}) names unknown platform "
                f"{platform!r}{suggest(platform, platforms)} (platforms: {', '.join(platforms)})"
            )


def check_initial_loads(world: Any, scenario: Scenario, where: str) -> None:
    """A platform's load of a resource at the start has one value: a load walk or load steps
    start where the scenario's ``initial`` LoadChange puts it, where it gives one (the run
    had started the walk at its own value, the checker at the initial one, and analyze
    refused the two)."""
    initial = {(ev.platform, ev.resource): ev.amount for ev in scenario.initial if isinstance(ev, LoadChange)}
    for kind, walks in (("load walk", world.load_walks), ("load steps", world.load_steps)):
        for w in walks:
            given = initial.get((w.platform, w.resource))
            if given is not None and float(given) != float(w.start):
                raise ScenarioError(
                    f"{where}: the {kind} of {w.platform!r} {w.resource} {'start' if kind == 'load steps' else 'starts'} at {w.start:g}, but the scenario's initial "
                    f"'{LoadChange(w.platform, given, w.resource)}' puts it at {given:g}: give them the same value"
                )


def refuse_together(faults: Any, loads: Any, changes: Any) -> None:
    """A :class:`~desmon.model.events.Together` (the checker's step of two changes) among a
    World's timed events is refused: the World times each change, and answers those of
    one instant in one reaction."""
    for where, timed in (("faults", faults), ("loads", loads), ("changes", changes)):
        for te in timed if isinstance(timed, (tuple, list)) else ():
            if isinstance(getattr(te, "event", None), Together):
                raise ScenarioError(
                    f"world: {where} holds '{te.event}' at t={te.time:g}: give its two changes as two timed events at that "
                    "time (the world answers the changes of one instant in one reaction)"
                )
