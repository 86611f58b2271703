# args: run {case}
# exit: 2
# expect: mttf for unknown component 'lwr_wrnch'
# expect: did you mean 'lwr_wrench'
"""A bad-input case: see tests/test_bad_inputs.py. An MTTF on a misspelt device."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.sim.world import LoadWalk, MTTF, Slip, StartFailure, Step, World
from desmon.model.scenario import TimedEvent
from desmon.model.events import DeviceFail, DeviceRepair, LoadChange, PlatformDown
scenario = Scenario(name='bad', model=care_o_bot().build(), world=World(task=(Step('grasp', 2.0), Step('hold', 8.0)), horizon=10.0, stochastic_faults=(MTTF('lwr_wrnch', mttf=100, mttr=10),)))
