# args: verify {case}
# exit: 2
# expect: deployment specification of 'a' has two Capacity requirements on 'memory': a graph consumes one amount of a resource
"""A bad-input case: see tests/test_bad_inputs.py. Placement checked 100 MB and 200 MB free
each on their own, and the run charged 300 MB: two graphs over-committed a 512 MB platform."""
from desmon.model import RobotBuilder

robot = RobotBuilder("r")
robot.platform("arm_pc", memory=512).device("ft", kind="force_sensor")
with robot.rpsl.perception_graph("a") as g:
    g.sensor("w", reads="force_sensor")
robot.depsl.deployment_specification("a").add_constraint("capacity", "memory", 100).add_constraint("capacity", "memory", 200)
robot.rules({"hold": "a"})
from desmon.model.scenario import Scenario  # noqa: E402

scenario = Scenario(name="cap", model=robot.build())
