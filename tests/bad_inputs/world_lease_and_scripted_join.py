# args: run {case}
# exit: 2
# expect: platform 'edge' has two masters of its presence
# expect: let the lease drive it, or script its joins, not both
"""A bad-input case: see tests/test_bad_inputs.py. A leased platform whose joins are also scripted."""
from desmon.model.cob3 import care_o_bot
from desmon.model.events import PlatformJoin
from desmon.model.scenario import Scenario, TimedEvent
from desmon.sim.world import Lease, Step, World
robot = care_o_bot()
robot.platform('edge', memory=2048, on_demand=True, startup_s=20)
world = World(task=(Step('grasp', 2.0),), horizon=100.0, lease=Lease(idle_s=60.0), changes=(TimedEvent(30.0, PlatformJoin('edge')),))
scenario = Scenario(name='bad', model=robot.build(), world=world)
