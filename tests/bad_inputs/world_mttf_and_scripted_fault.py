# args: run {case}
# exit: 2
# expect: world: 'lwr_wrench' has two masters of its failures: an MTTF and the scripted 'device lwr_wrench fails' at t=5 in faults=
"""A bad-input case: see tests/test_bad_inputs.py. The MTTF's repairs cut the scripted 20 s outage short."""
from desmon.model.cob3 import care_o_bot
from desmon.model.events import DeviceFail, DeviceRepair
from desmon.model.scenario import Scenario, TimedEvent
from desmon.sim.world import MTTF, Step, World
world = World(task=(Step('grasp', 2.0), Step('hold', 28.0)), horizon=30.0,
              faults=(TimedEvent(5.0, DeviceFail('lwr_wrench')), TimedEvent(25.0, DeviceRepair('lwr_wrench'))),
              stochastic_faults=(MTTF('lwr_wrench', mttf=2.0, mttr=1.0),))
scenario = Scenario(name='bad', model=care_o_bot().build(), world=world)
