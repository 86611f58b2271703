# args: run {case}
# exit: 2
# expect: load walk of 'arm_pc' every 1e-06 s over the horizon of 10 s is more than the 100,000 steps a run simulates; give a shorter horizon, or an interval of at least 0.0001 s
"""A bad-input case: see tests/test_bad_inputs.py. The run hung, growing past 800 MB."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.sim.world import LoadWalk, Step, World
world = World(task=(Step('grasp', 2.0), Step('hold', 8.0)), horizon=10.0, load_walks=(LoadWalk('arm_pc', start=300, sigma=1.0, interval=1e-6),))
scenario = Scenario(name='bad', model=care_o_bot().build(), world=world)
