# args: analyze {case} --transient-only
# exit: 2
# expect: its World's StartFailure(probability=1) fails every start, so no detector ever runs; give a probability below 1
"""A bad-input case: see tests/test_bad_inputs.py. --start-failure-p 1 is refused the same way."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.sim.world import MTTF, StartFailure, Step, World
from desmon.verify.bounds import Bounds
world = World(task=(Step('grasp', 2.0), Step('hold', 8.0), Step('release', 2.0), Step('idle', 3.0)), horizon=60.0, repeat=True,
              start_failure=StartFailure(probability=1.0), stochastic_faults=(MTTF('lwr_wrench', mttf=600, mttr=60),))
scenario = Scenario(name='certain', model=care_o_bot().build(), world=world,
                    checker=Bounds(task={'grasp': ('hold',), 'hold': ('release',), 'release': ('idle',), 'idle': ('grasp',)}, devices=('lwr_wrench',)))
