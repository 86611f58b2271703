"""Two edge boxes declared interchangeable host the vision detector; one of them may go down.

With the defaults the boxes are alike, and ``--symmetry`` applies. Two parameters make
them tell apart in ways the symmetry reduction must see and refuse:

- ``owners=True``: the model holds two robots (as a fleet's merged model does), and each
  box's camera belongs to another robot; the vision detector is robot r1's, so it reads
  e1's camera only.
- ``avoid=True``: the detector's specification has a requirement of a kind written here,
  ``avoid``, which reads a platform's name (never e2) and does not declare itself
  symmetric.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from desmon.errors import ModelError
from desmon.model import HOLD, MOVE_BASE, RobotBuilder
from desmon.model.checks import strict_init
from desmon.model.events import ActionChange
from desmon.model.kinds import Requirement
from desmon.model.params import parameters
from desmon.model.scenario import Scenario, TimedEvent
from desmon.verify.bounds import Bounds

p = parameters(owners=False, avoid=False)


@strict_init(ModelError)
@dataclass(frozen=True, slots=True)
class Avoid(Requirement):
    """The platform is not ``platform`` (it reads the name: not symmetric)."""

    platform: str
    word = "avoid"
    usage = "write ('avoid', platform)"

    def describe(self) -> str:
        return f"Avoid({self.platform})"

    def holds(self, state, graph):  # type: ignore[no-untyped-def]
        return "avoided" if state.platform.name == self.platform else None


VISION = "vision"
robot = RobotBuilder("r")
robot.platform("arm_pc", memory=512)
robot.platform("e1", memory=200).device("cam_1", kind="camera")
robot.platform("e2", memory=200).device("cam_2", kind="camera")
with robot.rpsl.perception_graph(VISION) as g:
    g.sensor("input", reads="camera")
    g.processing("detect", inputs=["input"])
spec = robot.depsl.deployment_specification(VISION).add_constraint("capacity", "memory", 150)
if not p.owners:
    spec.add_constraint("attribute", "platform_has", "camera")
if p.avoid:
    spec.add_constraint("avoid", "e2")
robot.rules({HOLD: [VISION]})
model = robot.build()
if p.owners:
    model = dataclasses.replace(model, owners=((VISION, "r1"), ("cam_1", "r1"), ("cam_2", "r2")))

scenario = Scenario(
    name="interchangeable_edge_boxes",
    description="two edge boxes declared interchangeable; one may go down",
    model=model,
    timeline=(TimedEvent(0.0, ActionChange(HOLD), "the robot holds"),),
    checker=Bounds(actions=(HOLD, MOVE_BASE), platforms=("e1", "e2"), max_failures=1, interchangeable=(("e1", "e2"),)),
)
