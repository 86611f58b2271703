# args: run {case}
# exit: 2
# expect: world: faults holds 'platform arm_pc down + device lwr_wrench fails' at t=5: give its two changes as two timed events at that time (the world answers the changes of one instant in one reaction)
"""A bad-input case: see tests/test_bad_inputs.py. A Together is the checker's step; the
world times each change and answers those of one instant in one reaction."""
from desmon.model.cob3 import care_o_bot
from desmon.model.events import DeviceFail, PlatformDown, Together
from desmon.model.scenario import Scenario, TimedEvent
from desmon.sim.world import Step, World
world = World(task=(Step('grasp', 2.0), Step('hold', 8.0)), horizon=10.0,
              faults=(TimedEvent(5.0, Together(PlatformDown('arm_pc'), DeviceFail('lwr_wrench'))),))
scenario = Scenario(name='bad', model=care_o_bot().build(), world=world)
