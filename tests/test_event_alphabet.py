"""An event kind with a new checker variable, defined in this file only.

The kinds ``device_unplug`` and ``device_plug`` (a device pulled out of its socket and
plugged back in) are :class:`~desmon.model.events.DeviceEvent` classes; the variable
kind ``socket`` (:class:`~desmon.verify.environment.VariableKind`) makes each device
listed in ``Bounds(variables={"socket": (...)})`` a variable of the checker: unplugged
at any time (no failure budget), plugged back at any time (``repair`` does not apply).
Its kind also lists every event of a socket (the fuzzer's raw events draw them) and
gives each a rate (a socket is unplugged after a mean of ``PLUGGED_S`` and plugged back
after ``UNPLUGGED_S``). Nothing else is written for them: the direct engine and the
table engine explore them with the same result, the symmetry reduction renames them,
the simulation runs them in a timeline, reacting as the checker's transitions do,
``desmon fuzz`` and the strategies draw them, and ``desmon analyze``'s chain times them
(without rates it refuses them in one line).
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
#: mean seconds a socket stays plugged in, and unplugged
PLUGGED_S, UNPLUGGED_S = 600.0, 60.0


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
        rate = "PLUGGED_S and UNPLUGGED_S (the socket's means)"

        def problem(self, subjects: tuple[Any, ...], scenario: Any) -> str | None:
            devices = [d.name for d in scenario.model.devices]
            unknown = [d for d in subjects if d not in devices]
            return f"unknown device {unknown[0]!r}" if unknown else None

        def enabled(self, b: Any, key: Key, d: str, room: bool) -> list[Event]:
            return [DevicePlugged(d) if d in key.failed else DeviceUnplugged(d)]

        def every_event(self, b: Any, d: str) -> tuple[Event, ...]:
            return (DeviceUnplugged(d), DevicePlugged(d))

        def event_to(self, b: Any, d: str, unplugged: bool) -> Event:
            return DeviceUnplugged(d) if unplugged else DevicePlugged(d)

        def rates(self, world: Any, b: Any, d: str) -> tuple[tuple[Event, float], ...]:
            return ((DeviceUnplugged(d), 1.0 / PLUGGED_S), (DevicePlugged(d), 1.0 / UNPLUGGED_S))

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


def test_a_kind_moving_a_fact_the_checker_has_no_rule_for_is_refused_by_symmetry_and_the_table_engine(socket, monkeypatch):  # type: ignore[no-untyped-def]
    # both read what the variables move in one place (environment.moved): a fact neither knows
    # (here a made-up "socket" fact of the device) cannot be shown alike on interchangeable platforms
    kind = type(variable_kind("socket"))
    monkeypatch.setattr(kind, "digits", lambda self, b, d: (Digit("socket", d),))
    grouped = Bounds(actions=(HOLD, GRASP), variables={"socket": ("thermo", "thermo2")}, interchangeable=(("body_pc", "spare_pc"),))
    with pytest.raises(CheckerError, match="the bounds' socket variables do not say what they move"):
        Checker(replace(_scenario(), checker=grouped), symmetry=True)
    with pytest.raises(CheckerError, match="no array operations for the environment's socket events"):
        Checker(_scenario()).run(engine="table")


def test_bounds_refuse_an_unknown_kind_or_subject(socket):  # type: ignore[no-untyped-def]
    with pytest.raises(CheckerError, match="variables names 'sockets', which is no kind of variable read from there \\(did you mean 'socket'\\?\\)"):
        Scenario(name="kiln", model=_robot().build(), checker=Bounds(actions=(HOLD,), variables={"sockets": ("thermo",)}))
    with pytest.raises(CheckerError, match=r"variables\['socket'\]: unknown device 'thermos'"):
        Scenario(name="kiln", model=_robot().build(), checker=Bounds(actions=(HOLD,), variables={"socket": ("thermos",)}))


def _analysable(**bounds: Any) -> Scenario:
    from desmon.sim.world import Step, World

    return replace(_scenario(**bounds), world=World(task=(Step(HOLD, 10.0), Step(GRASP, 5.0)), horizon=60.0, repeat=True))


def test_analyze_times_it_by_its_rates(socket):  # type: ignore[no-untyped-def]
    from desmon.analyze.chain import build_chain
    from desmon.analyze.markov import markov_world
    from desmon.analyze.solve import steady_state

    unplugged, plugged = socket
    mw = markov_world(_analysable())
    assert [(k, s, [str(e) for e, _r in rates]) for k, s, rates in mw.timed] == [
        ("socket", "thermo", ["device thermo unplugged", "device thermo plugged in"]),
        ("socket", "thermo2", ["device thermo2 unplugged", "device thermo2 plugged in"]),
    ]
    chain = build_chain(_analysable(), "desmon", mw)
    # the world and the repository see an unplug at once: a state's physical and known sockets agree
    assert all(s.phys_failed == s.key.failed for s in chain.states)
    assert {s.phys_failed for s in chain.states} == {(), ("thermo",), ("thermo2",), ("thermo", "thermo2")}
    Q, _exit = chain.generator()
    pi, _residual, _method = steady_state(Q, chain.describe)
    out = sum(p for p, s in zip(pi, chain.states) if "thermo" in s.phys_failed)
    # each socket alone is a two-state chain: unplugged for UNPLUGGED_S out of every PLUGGED_S + UNPLUGGED_S
    assert out == pytest.approx(UNPLUGGED_S / (PLUGGED_S + UNPLUGGED_S), rel=1e-9)
    both = sum(p for p, s in zip(pi, chain.states) if len(s.phys_failed) == 2)
    assert both == pytest.approx(out**2, rel=1e-9)  # the two sockets move independently
    assert any(g == GRAPH and p == "spare_pc" for s in chain.states for g, p in s.key.deployments if "thermo" in s.phys_failed)


def test_analyze_refuses_it_in_one_line_without_rates(socket, monkeypatch):  # type: ignore[no-untyped-def]
    from desmon.analyze.markov import AnalysisError, markov_world

    kind = type(variable_kind("socket"))
    monkeypatch.setattr(kind, "rates", lambda self, world, b, d: ())
    with pytest.raises(AnalysisError, match=r"the socket variable 'thermo' change, but its kind of variable gives its events no rates \(PLUGGED_S"):
        markov_world(_analysable())
    monkeypatch.setattr(kind, "rate", None)
    with pytest.raises(AnalysisError, match="the socket variable 'thermo' change, but nothing gives its events a rate"):
        markov_world(_analysable())


def test_fuzzing_draws_it(socket):  # type: ignore[no-untyped-def]
    from hypothesis import find, settings

    from desmon.verify.fuzz import fuzz, run_choices
    from desmon.verify.strategies import event_sequences, events

    unplugged, plugged = socket
    scenario = _scenario()
    # the raw events: every event of every kind's variables
    assert find(events(scenario), lambda e: e == plugged("thermo2"), settings=settings(database=None)) == plugged("thermo2")
    assert find(event_sequences(scenario), lambda seq: unplugged("thermo") in seq and ActionChange(GRASP) in seq, settings=settings(database=None))
    # the fuzzer's sequences pick among the enabled events, the socket's among them
    checker = Checker(scenario)
    enabled = checker.enabled(checker.system.initial())
    pick = enabled.index(unplugged("thermo"))
    labels, bad = run_choices(scenario, "desmon", [(pick, ()), (enabled.index(unplugged("thermo2")), ())], checker)
    assert bad is None and [e for e, _f in labels] == [unplugged("thermo"), unplugged("thermo2")]
    outcome = fuzz(scenario, examples=40, seed=1)
    assert outcome.exit_code == 0 and outcome.passed == 40, outcome.text


def test_the_table_moves_agree_with_event_to_on_every_kind(socket):  # type: ignore[no-untyped-def]
    """Each array operation moves a variable to a value by the event its kind names for that value."""
    from desmon.loader import load_scenario
    from desmon.verify.bounds import bounds_of
    from desmon.verify.environment import variables
    from pathlib import Path

    scenarios = [_scenario()] + [load_scenario(p) for p in sorted((Path(__file__).resolve().parent.parent / "scenarios").glob("*.py"))]
    seen = set()
    for scenario in scenarios:
        b = bounds_of(scenario)
        contexts = [None, *(tuple(b.actions) or tuple(b.task or ()))]
        for v in variables(b):
            kind = variable_kind(v.kind)
            assert kind is not None
            digits = kind.digits(b, v.subject)
            if v.kind == "requirements" or digits is None:
                continue

            def values(d: Digit) -> list[Any]:
                return contexts if d.fact == "context" else list(d.levels) if d.fact == "load" else [False, True]

            for move in kind.moves(b, v.subject, values):
                vals = values(move.digit)
                for to, event in zip(move.to, move.events):
                    if to >= 0:
                        assert event == kind.event_to(b, v.subject, vals[to]), (scenario.name, v, vals[to])
                        assert event in kind.every_event(b, v.subject)
                        seen.add(v.kind)
    assert seen == {"action", "device", "platform", "load", "join", "socket"}


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


def test_what_the_variables_move_is_read_in_order_up_to_the_first_thing_it_cannot_read():
    """environment.moved, which the table engine's encoding and the symmetry conditions both
    read: a load moved over two sets of levels ends the reading there (a later kind's
    digits are not read), and so does a digit naming a device the model lacks."""
    from desmon.errors import TableUnsupported
    from desmon.loader import load_scenario
    from desmon.verify.environment import moved
    from desmon.verify.table.encoding import layout

    class Surge(VariableKind):
        name = "surge_levels"

        def digits(self, b: Any, p: str) -> tuple[Digit, ...]:
            return (Digit("load", p, (0.0, 999.0)),)

    class Ghost(VariableKind):
        name = "ghost_device"

        def digits(self, b: Any, subject: str) -> tuple[Digit, ...]:
            return (Digit("device", "no_such_device"),)

    try:
        sc = load_scenario("scenarios/coffee_handover.py")
        b, model = Checker(sc).bounds, sc.model
        p = model.platforms[0].name
        clash = replace(b, loads={p: (0.0, 50.0)}, variables={"surge_levels": (p,), "ghost_device": ("x",)})
        assert (moved(clash, model).clash, moved(clash, model).unknown) == (p, "")
        with pytest.raises(TableUnsupported, match=f"two kinds of variable move the load of {p} over different levels"):
            layout(clash, model)
        ghost = replace(b, variables={"ghost_device": ("x",)})
        assert (moved(ghost, model).clash, moved(ghost, model).unknown) == ("", "ghost_device")
        with pytest.raises(TableUnsupported, match="no array operations for the environment's ghost_device events"):
            layout(ghost, model)
    finally:
        Surge.unregister()
        Ghost.unregister()
