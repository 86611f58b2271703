# args: run {case}
# exit: 2
# expect: world: the memory load of 'arm_pc' has two masters: a load walk and the scripted 'load arm_pc memory=450' at t=4 in loads=
"""A bad-input case: see tests/test_bad_inputs.py. The walk's next step overwrote the scripted load at once."""
from desmon.model.cob3 import care_o_bot
from desmon.model.events import LoadChange
from desmon.model.scenario import Scenario, TimedEvent
from desmon.sim.world import LoadWalk, Step, World
world = World(task=(Step('grasp', 2.0), Step('hold', 8.0)), horizon=10.0, loads=(TimedEvent(4.0, LoadChange('arm_pc', 450)),),
              load_walks=(LoadWalk('arm_pc', start=300, sigma=0.0, interval=1.0),))
scenario = Scenario(name='bad', model=care_o_bot().build(), world=world)
