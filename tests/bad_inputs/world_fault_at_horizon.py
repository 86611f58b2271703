# args: run {case}
# exit: 2
# expect: fault 'device lwr_wrench fails' at t=10 is at or after the horizon
"""A bad-input case: see tests/test_bad_inputs.py. A fault at the horizon used to be dropped silently."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.sim.world import LoadWalk, MTTF, Slip, StartFailure, Step, World
from desmon.model.scenario import TimedEvent
from desmon.model.events import DeviceFail, DeviceRepair, LoadChange, PlatformDown
scenario = Scenario(name='bad', model=care_o_bot().build(), world=World(task=(Step('grasp', 2.0), Step('hold', 8.0)), horizon=10.0, faults=(TimedEvent(10.0, DeviceFail('lwr_wrench')),)))
