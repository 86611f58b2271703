# args: run {case}
# exit: 2
# expect: lease platforms name 'edge' twice
"""A bad-input case: see tests/test_bad_inputs.py. A lease naming its platform twice."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario, TimedEvent
from desmon.model.events import RequirementChange
from desmon.model.requirements import Capacity
from desmon.sim.world import Lease, RandomChanges, Step, World
robot = care_o_bot()
robot.platform('edge', memory=2048, on_demand=True, startup_s=20)
FAST = RequirementChange('combined_slip_detector', add=(Capacity('memory', 350),), remove=(Capacity('memory', 250),))
scenario = Scenario(name='bad', model=robot.build(), world=World(task=(Step('grasp', 2.0),), horizon=10.0, lease=Lease(platforms=('edge', 'edge'))))
