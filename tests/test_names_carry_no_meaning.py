"""A component's name is only a name: a device named like a platform, or a platform named
``context``, gives the same run as any other names would. (Under exponential timing the
context monitor keeps one pending notice per component: of a device, of a platform, and
the recognition of the action; none of them may stand in for another.)"""

from __future__ import annotations

import pytest

from desmon.model import RobotBuilder
from desmon.model.events import PlatformDown
from desmon.model.scenario import Scenario, TimedEvent
from desmon.sim.engine import simulate
from desmon.sim.world import Step, World


def _scenario(device: str, second: str) -> Scenario:
    """A force detector on ``second`` (preferred) or pc1 (which has the sensor ``device``);
    ``second`` goes down at 5 s and the detector must move."""
    robot = RobotBuilder("r")
    robot.platform("pc1", memory=512).device(device, kind="force_sensor")
    robot.platform(second, memory=512, preference=1.0)
    with robot.rpsl.perception_graph("force") as g:
        g.sensor("w", reads="force_sensor")
    robot.depsl.deployment_specification("force").add_constraint("capacity", "memory", 100)
    robot.rules({"hold": "force"})
    world = World(task=(Step("idle", 1.0), Step("hold", 19.0)), horizon=20.0, repeat=True, timing="exponential", signals=False,
                  faults=(TimedEvent(5.0, PlatformDown(second)),), heartbeat_timeout=0.2, recognition_delay=0.5)
    return Scenario(name="names", model=robot.build(), world=world)


def _figures(sc: Scenario, seed: int) -> tuple:
    m = simulate(sc, "desmon", seed=seed).metrics
    return m["unmonitored_exposure_s"], m["risky_time_s"], tuple(sorted(m["unmonitored_by_cause_s"].items())), m["switches"]


@pytest.mark.parametrize("seed", [0, 2])
@pytest.mark.parametrize("device, second", [("pc2", "pc2"), ("ft", "context")])
def test_a_device_named_like_a_platform_or_a_platform_named_context_changes_nothing(device, second, seed):
    assert _figures(_scenario(device, second), seed) == _figures(_scenario("ft", "pc2"), seed)
