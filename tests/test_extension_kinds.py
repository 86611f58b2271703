"""Adding an event kind and a sensor stream touches no file of desmon/.

Each is defined here only (docs/design.md, "Recipe: a new event kind" and "Recipe: a new
sensor stream"), inside a fixture that unregisters it afterwards so the other tests see
the built-in kinds only:

* ``DeviceUnplugged`` (kind ``device_unplug``): a device pulled out of its socket. It is
  a :class:`~desmon.model.events.DeviceEvent` (the device stops working), with its own
  kind name, description and JSON; it runs in a scenario timeline through the SimPy
  world (a scripted fault) and the scripted replay, and reads back from JSON.
* ``TemperatureStream`` (stream ``temperature``, device kind ``thermometer``) with an
  overheat detector consuming it: a graph reading a thermometer runs that detector in a
  simulation run, warms up, and alarms when the temperature crosses 40 degrees.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import Any, Iterator, Sequence

import numpy as np
import pytest

from desmon.detectors.base import Alarm
from desmon.errors import ModelError
from desmon.model import HOLD, RobotBuilder
from desmon.model.checks import strict_init
from desmon.model.events import ActionChange, DeviceEvent, Event, event_kind
from desmon.model.scenario import Scenario, TimedEvent
from desmon.sim.engine import simulate
from desmon.sim.streams import SignalStream
from desmon.sim.world import Step, World
from desmon.verify.report import event_from_json, event_to_json

GRAPH = "overheat_detector"


def _robot() -> RobotBuilder:
    robot = RobotBuilder("kiln-robot")
    robot.platform("body_pc", memory=512).device("thermo", kind="thermometer", vendor="acme")
    robot.platform("spare_pc", memory=512)
    with robot.rpsl.perception_graph(GRAPH) as g:
        g.sensor("temperature", reads="thermometer")
        g.processing("threshold", inputs=["temperature"])
    robot.depsl.deployment_specification(GRAPH).add_constraint("attribute", "platform_has", "thermometer")
    robot.rules({HOLD: GRAPH})
    return robot


# -- a new event kind -------------------------------------------------------------------------
@pytest.fixture()
def unplugged() -> Iterator[type[Event]]:
    @strict_init(ModelError)
    @dataclass(frozen=True, slots=True)
    class DeviceUnplugged(DeviceEvent):
        """A device pulled out of its socket: it stops working, like a failure."""

        kind = "device_unplug"
        working = False
        device: str

        def __str__(self) -> str:
            return f"device {self.device} unplugged"

    try:
        yield DeviceUnplugged
    finally:
        DeviceUnplugged.unregister()
    assert Event.of_kind("device_unplug") is None


def test_a_new_event_kind_registers_itself_and_leaves_when_asked(unplugged):  # type: ignore[no-untyped-def]
    assert Event.of_kind("device_unplug") is unplugged
    assert unplugged in Event.kinds()
    assert event_kind(unplugged("thermo")) == "device_unplug"
    with pytest.raises(ModelError, match="DeviceUnplugged device '' is not a name"):
        unplugged("")


def test_a_new_event_kind_reads_back_from_json(unplugged):  # type: ignore[no-untyped-def]
    e = unplugged("thermo")
    data = event_to_json(e)
    assert data == {"kind": "device_unplug", "device": "thermo"}
    assert event_from_json(json.loads(json.dumps(data))) == e
    with pytest.raises(Exception, match="unknown key 'platform'"):
        event_from_json({"kind": "device_unplug", "device": "thermo", "platform": "x"})


def test_a_new_event_kind_is_checked_against_the_model(unplugged):  # type: ignore[no-untyped-def]
    with pytest.raises(ModelError, match="device thermos unplugged names unknown device 'thermos'"):
        Scenario(name="kiln", model=_robot().build(), timeline=(TimedEvent(1.0, unplugged("thermos")),))


def test_a_new_event_kind_runs_in_a_scenario_timeline_of_the_simulation(unplugged):  # type: ignore[no-untyped-def]
    scenario = Scenario(
        name="kiln",
        model=_robot().build(),
        timeline=(TimedEvent(0.0, ActionChange(HOLD), "t0"), TimedEvent(3.0, unplugged("thermo"), "t1")),
    )
    run = simulate(scenario)  # the world is derived from the timeline: the new kind is a scripted fault
    records = [r for r in run.trace.records]
    faults = [r for r in records if r["type"] == "fault"]
    assert [(r["t"], r["event"]) for r in faults] == [(3.0, "device thermo unplugged")]
    assert any(r["type"] == "fact" and r["fact"] == "device thermo unplugged" for r in records)
    # the monitor wrote the fact: the deployer lost its only thermometer and said so
    assert [d["command"] for d in run.decisions][:1] == ["start"]
    assert any(d["command"] == "stop" and d["t"] >= 3.0 for d in run.decisions)
    assert any(e.time >= 3.0 for e in run.errors)

    from desmon.sim.replay import format_replay, replay  # the scripted replay (desmon replay) reads the same timeline

    text = format_replay(replay(scenario))
    assert "device thermo unplugged" in text and "no_acceptable_platforms" in text, text


# -- a new sensor stream ----------------------------------------------------------------------
class OverheatDetector:
    """Alarms once each time the temperature rises above ``limit``."""

    def __init__(self, name: str, limit: float = 40.0) -> None:
        self.name = name
        self.limit = limit
        self.hot = False

    def activate(self, t: float) -> None:
        self.hot = False

    def deactivate(self) -> None:
        self.hot = False

    def process(self, times: np.ndarray, values: np.ndarray, until: float | None = None) -> tuple[Alarm, ...]:
        out = []
        for t, v in zip(times.tolist(), values.tolist()):
            if v > self.limit and not self.hot:
                out.append(Alarm(t, self.name, None))
            self.hot = v > self.limit
        return tuple(out)


@pytest.fixture()
def temperature() -> Iterator[type[SignalStream]]:
    class TemperatureStream(SignalStream):
        """A thermometer at 10 Hz: 20 degrees, 50 from t = 6 s on."""

        name = "temperature"
        warmup = 0.2
        device_kinds = ("thermometer",)

        @classmethod
        def samples(cls, bank: Any, t0: float, t1: float, devices: Sequence[str]) -> tuple[Any, ...]:
            k = np.arange(math.ceil(t0 * 10 - 1e-9), math.ceil(t1 * 10 - 1e-9))
            times = k / 10.0
            values = np.where(times >= 6.0, 50.0, 20.0)
            working = np.array([any(bank.working(d, t) for d in devices) for t in times.tolist()], dtype=bool)
            return times[working], values[working]

        @classmethod
        def detector(cls, name: str) -> Any:
            return OverheatDetector(name)

    try:
        yield TemperatureStream
    finally:
        TemperatureStream.unregister()


def _kiln_world(**kw: Any) -> World:
    return World(task=(Step(HOLD, 10.0),), horizon=10.0, signal_kinds={"thermometer": "temperature"}, **kw)


def test_a_new_stream_feeds_its_detector_in_a_simulation_run(temperature):  # type: ignore[no-untyped-def]
    scenario = Scenario(name="kiln", model=_robot().build(), world=_kiln_world())
    run = simulate(scenario)
    assert [(a.time, a.detector) for a in run.alarms] == [(6.0, GRAPH)]
    ready = [r for r in run.trace.records if r["type"] == "ready"]
    assert [(r["t"], r["graph"]) for r in ready] == [(0.2, GRAPH)]  # the stream's warm-up


def test_a_new_stream_is_silent_while_its_device_is_failed(temperature):  # type: ignore[no-untyped-def]
    from desmon.model.events import DeviceFail, DeviceRepair

    faults = (TimedEvent(5.0, DeviceFail("thermo")), TimedEvent(7.0, DeviceRepair("thermo")))
    scenario = Scenario(name="kiln", model=_robot().build(), world=_kiln_world(faults=faults))
    run = simulate(scenario)
    assert [a.time for a in run.alarms] == [7.0]  # hot from 6 s, but read again only from 7 s


def test_an_unknown_stream_is_refused_once_the_stream_class_is_gone():
    with pytest.raises(Exception, match="which is no signal stream: use one of wrench, tactile"):
        _kiln_world()
