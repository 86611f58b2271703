"""An event kind with a new checker variable, defined in this file only.

The kinds ``device_unplug`` and ``device_plug`` (a device pulled out of its socket and
plugged back in) are :class:`~desmon.model.events.DeviceEvent` classes; the variable
kind ``socket`` (:class:`~desmon.verify.environment.VariableKind`) makes each device
listed in ``Bounds(variables={"socket": (...)})`` a variable of the checker: unplugged
at any time (no failure budget), plugged back at any time (``repair`` does not apply).
Nothing else is written for them: the direct engine and the table engine explore them
with the same result, the symmetry reduction renames them, ``desmon analyze`` refuses
them in one line (their kind names no rate), and the simulation runs them in a
timeline, reacting as the checker's transitions do.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Callable, Iterator, Sequence

import pytest

from desmon.errors import CheckerError, ModelError
from desmon.model import GRASP, HOLD, RobotBuilder
from desmon.model.checks import strict_init
from desmon.model.events import ActionChange, DeviceEvent, Event
from desmon.model.scenario import Scenario, TimedEvent
from desmon.verify import Bounds, Checker
from desmon.verify.environment import Digit, Move, VariableKind, alphabet, event_kinds, variable_kind
from desmon.verify.state import Key

GRAPH = "overheat_detector"


def _robot() -> RobotBuilder:
    robot = RobotBuilder("kiln-robot")
    robot.platform("body_pc", memory=512).device("thermo", kind="thermometer", vendor="acme")
    robot.platform("spare_pc", memory=512).device("thermo2", kind="thermometer", vendor="acme")
    with robot.rpsl.perception_graph(GRAPH) as g:
        g.sensor("temperature", reads="thermometer")
        g.processing("threshold", inputs=["temperature"])
    robot.depsl.deployment_specification(GRAPH).add_constraint("attribute", "platform_has", "thermometer")
    robot.rules({HOLD: GRAPH, GRASP: GRAPH})
    return robot


@pytest.fixture()
def socket() -> Iterator[tuple[type[Event], type[Event]]]:
    @strict_init(ModelError)
    @dataclass(frozen=True, slots=True)
    class DeviceUnplugged(DeviceEvent):
        kind = "device_unplug"
        working = False
        device: str

        def __str__(self) -> str:
            return f"device {self.device} unplugged"

    @strict_init(ModelError)
    @dataclass(frozen=True, slots=True)
    class DevicePlugged(DeviceEvent):
        kind = "device_plug"
        working = True
        device: str

        def __str__(self) -> str:
            return f"device {self.device} plugged in"

    class SocketVariable(VariableKind):
        """A device's socket: unplugged while plugged in, plugged in while unplugged."""

        name = "socket"
        events = (DeviceUnplugged, DevicePlugged)
        symmetric = True

        def problem(self, subjects: tuple[Any, ...], scenario: Any) -> str | None:
            devices = [d.name for d in scenario.model.devices]
            unknown = [d for d in subjects if d not in devices]
            return f"unknown device {unknown[0]!r}" if unknown else None

        def enabled(self, b: Any, key: Key, d: str, room: bool) -> list[Event]:
            return [DevicePlugged(d) if d in key.failed else DeviceUnplugged(d)]

        def digits(self, b: Any, d: str) -> tuple[Digit, ...]:
            return (Digit("device", d),)

        def moves(self, b: Any, d: str, values: Callable[[Digit], Sequence[Any]]) -> list[Move]:
            return [Move(Digit("device", d), (1, 0), (DeviceUnplugged(d), DevicePlugged(d)), (False, False))]

        def rename(self, event: Event, platform: Callable[[str], str], device: Callable[[str], str]) -> Event:
            return type(event)(device(event.device))  # type: ignore[attr-defined, call-arg]

    try:
        yield DeviceUnplugged, DevicePlugged
    finally:
        SocketVariable.unregister()
        DeviceUnplugged.unregister()
        DevicePlugged.unregister()
    assert variable_kind("socket") is None and "device_unplug" not in event_kinds()


def _scenario(timeline: tuple[TimedEvent, ...] = (), **bounds: Any) -> Scenario:
    b = Bounds(actions=(HOLD, GRASP), variables={"socket": ("thermo", "thermo2")}, **bounds)
    return Scenario(name="kiln", model=_robot().build(), timeline=timeline, checker=b)


def test_the_kind_joins_the_alphabet_and_leaves_when_asked(socket):  # type: ignore[no-untyped-def]
    unplugged, plugged = socket
    assert alphabet()[-2:] == (unplugged, plugged)
    assert event_kinds()[-2:] == ("device_unplug", "device_plug")


def test_both_engines_explore_it_with_the_same_result(socket):  # type: ignore[no-untyped-def]
    results = {engine: Checker(_scenario()).run(engine=engine) for engine in ("direct", "table")}
    direct, table = results["direct"], results["table"]
    assert table.engine == "table" and not table.engine_note
    assert (table.verdict, table.states, table.transitions) == (direct.verdict, direct.states, direct.transitions)
    assert table.enabled == direct.enabled and table.new_states == direct.new_states and table.changed == direct.changed
    assert direct.enabled["device_unplug"] and direct.enabled["device_plug"]
    assert direct.new_states["device_unplug"] and direct.changed["device_plug"]


def test_the_engines_agree_state_by_state(socket):  # type: ignore[no-untyped-def]
    direct, table = Checker(_scenario()), Checker(_scenario())
    direct.run(engine="direct")
    table.run(engine="table")
    assert list(direct.explored) == list(table.explored)
    assert any("thermo" in k.failed and "thermo2" in k.failed for k in direct.explored)


def test_the_symmetry_reduction_reads_its_rule(socket):  # type: ignore[no-untyped-def]
    unplugged, _plugged = socket
    grouped = Bounds(actions=(HOLD, GRASP), variables={"socket": ("thermo", "thermo2")}, interchangeable=(("body_pc", "spare_pc"),))
    # the kind moves a device of a group platform (its digits): the group's platforms may differ
    with pytest.raises(CheckerError, match="device thermo of body_pc may fail"):
        Checker(replace(_scenario(), checker=grouped), symmetry=True)
    swap = {"body_pc": "spare_pc", "spare_pc": "body_pc"}
    kind = variable_kind("socket")
    assert kind is not None and kind.symmetric
    assert kind.rename(unplugged("thermo"), lambda p: swap.get(p, p), {"thermo": "thermo2"}.get) == unplugged("thermo2")


def test_bounds_refuse_an_unknown_kind_or_subject(socket):  # type: ignore[no-untyped-def]
    with pytest.raises(CheckerError, match="variables names 'sockets', which is no kind of variable read from there \\(did you mean 'socket'\\?\\)"):
        Scenario(name="kiln", model=_robot().build(), checker=Bounds(actions=(HOLD,), variables={"sockets": ("thermo",)}))
    with pytest.raises(CheckerError, match=r"variables\['socket'\]: unknown device 'thermos'"):
        Scenario(name="kiln", model=_robot().build(), checker=Bounds(actions=(HOLD,), variables={"socket": ("thermos",)}))


def test_analyze_refuses_it_in_one_line(socket):  # type: ignore[no-untyped-def]
    from desmon.analyze.markov import AnalysisError, markov_world
    from desmon.sim.world import Step, World

    scenario = replace(_scenario(), world=World(task=(Step(HOLD, 10.0), Step(GRASP, 5.0)), horizon=60.0, repeat=True))
    with pytest.raises(AnalysisError, match="the socket variable 'thermo' change, but nothing gives its events a rate"):
        markov_world(scenario)


def test_the_simulation_reacts_as_the_checker_transitions(socket):  # type: ignore[no-untyped-def]
    unplugged, plugged = socket
    from desmon.sim.engine import simulate

    events = (ActionChange(HOLD), unplugged("thermo"), plugged("thermo"), unplugged("thermo2"))
    scenario = _scenario(tuple(TimedEvent(2.0 * i, e, f"t{i}") for i, e in enumerate(events)))
    run = simulate(scenario)
    faults = [(r["t"], r["event"]) for r in run.trace.records if r["type"] == "fault"]
    assert faults == [(2.0, "device thermo unplugged"), (4.0, "device thermo plugged in"), (6.0, "device thermo2 unplugged")]
    simulated = [(d["command"], d["graph"], d["platform"]) for d in run.decisions]

    system = Checker(_scenario()).system
    key = system.initial()
    checked = []
    for event in events:
        key, _outcomes, log, _instant = system.run_one(key, event, ())
        checked += [(type(c).__name__.lower(), c.graph, c.platform) for c, ok in log.commands if ok and type(c).__name__ in ("Start", "Stop")]
    assert simulated == checked
    assert key.deployments == ((GRAPH, "body_pc"),)
