# args: verify {case}
# exit: 2
# expect: the World's load walk of 'arm_pc' memory starts at 300, but the scenario's initial gives 'arm_pc' no memory load, so the checker would start from 0 and the run from 300: add LoadChange('arm_pc', 300) to the scenario's initial
"""A bad-input case: see tests/test_bad_inputs.py. The checker's first state had no load on
arm_pc while every run started at 300 MB: a verdict about another start than the run's."""
from desmon.model.cob3 import care_o_bot
from desmon.model.events import ActionChange
from desmon.model.scenario import Scenario, TimedEvent
from desmon.sim.world import LoadWalk, Step, World
from desmon.verify.bounds import Bounds
world = World(task=(Step('grasp', 2.0), Step('hold', 8.0)), horizon=10.0,
              load_walks=(LoadWalk('arm_pc', start=300, sigma=0.0, interval=1.0),))
scenario = Scenario(name='bad', model=care_o_bot().build(), timeline=(TimedEvent(0.0, ActionChange('grasp'), 't0'),), world=world,
                    checker=Bounds(actions=('grasp', 'hold')))
