# args: run {case}
# exit: 2
# expect: world: task = step(
# expect: trailing comma
"""A bad-input case: see tests/test_bad_inputs.py. task=(Step(...)) without its comma."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.sim.world import LoadWalk, MTTF, Slip, StartFailure, Step, World
from desmon.model.scenario import TimedEvent
from desmon.model.events import DeviceFail, DeviceRepair, LoadChange, PlatformDown
scenario = Scenario(name='bad', model=care_o_bot().build(), world=World(task=(Step('grasp', 5.0)), horizon=5.0))
