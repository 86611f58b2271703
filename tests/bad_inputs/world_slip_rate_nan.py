# args: run {case}
# exit: 2
# expect: slip_rate = nan is not a number
"""A bad-input case: see tests/test_bad_inputs.py. NaN slip rate."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.sim.world import LoadWalk, MTTF, Slip, StartFailure, Step, World
from desmon.model.scenario import TimedEvent
from desmon.model.events import DeviceFail, DeviceRepair, LoadChange, PlatformDown
scenario = Scenario(name='bad', model=care_o_bot().build(), world=World(task=(Step('grasp', 2.0), Step('hold', 8.0)), horizon=10.0, slip_rate=float('nan')))
