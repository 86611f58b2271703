# args: run {case}
# exit: 2
# expect: MTTF of 'lwr_wrench' (mttf 1e-06 s, mttr 1e-06 s) gives about 10,000,000 failures and repairs over the horizon of 10 s, more than the 100,000 a run simulates
"""A bad-input case: see tests/test_bad_inputs.py. The run hung, growing past 1 GB."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.sim.world import MTTF, Step, World
world = World(task=(Step('grasp', 2.0), Step('hold', 8.0)), horizon=10.0, stochastic_faults=(MTTF('lwr_wrench', mttf=1e-6, mttr=1e-6),))
scenario = Scenario(name='bad', model=care_o_bot().build(), world=world)
