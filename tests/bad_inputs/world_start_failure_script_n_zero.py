# args: run {case}
# exit: 2
# expect: attempts count from 1
"""A bad-input case: see tests/test_bad_inputs.py. Attempt 0 never happens."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.sim.world import LoadWalk, MTTF, Slip, StartFailure, Step, World
from desmon.model.scenario import TimedEvent
from desmon.model.events import DeviceFail, DeviceRepair, LoadChange, PlatformDown
scenario = Scenario(name='bad', model=care_o_bot().build(), world=World(task=(Step('grasp', 2.0), Step('hold', 8.0)), horizon=10.0, start_failure=StartFailure(script=(('force_slip_detector', 'arm_pc', 0),))))
