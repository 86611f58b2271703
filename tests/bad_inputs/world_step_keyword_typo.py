# args: run {case}
# exit: 2
# expect: unknown keyword 'durration'
# expect: did you mean 'duration'
"""A bad-input case: see tests/test_bad_inputs.py. A misspelt dataclass keyword."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.sim.world import LoadWalk, MTTF, Slip, StartFailure, Step, World
from desmon.model.scenario import TimedEvent
from desmon.model.events import DeviceFail, DeviceRepair, LoadChange, PlatformDown
scenario = Scenario(name='bad', model=care_o_bot().build(), world=World(task=(Step('grasp', durration=2.0),), horizon=5.0))
