# args: run {case}
# exit: 2
# expect: start 900 is outside [low, high] = [200, 450]
"""A bad-input case: see tests/test_bad_inputs.py. A walk that starts outside its range."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.sim.world import LoadWalk, MTTF, Slip, StartFailure, Step, World
from desmon.model.scenario import TimedEvent
from desmon.model.events import DeviceFail, DeviceRepair, LoadChange, PlatformDown
scenario = Scenario(name='bad', model=care_o_bot().build(), world=World(task=(Step('grasp', 2.0), Step('hold', 8.0)), horizon=10.0, load_walks=(LoadWalk('arm_pc', start=900, sigma=10, interval=5.0, low=200, high=450),)))
