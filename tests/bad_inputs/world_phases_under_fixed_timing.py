# args: run {case}
# exit: 2
# expect: world: phases=4 with timing='fixed': Erlang phases time the task steps under timing='exponential'
"""A bad-input case: see tests/test_bad_inputs.py. The phases were ignored without a word (run --phases refuses the same)."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.sim.world import Step, World
world = World(task=(Step('grasp', 2.0), Step('hold', 8.0)), horizon=10.0, phases=4)
scenario = Scenario(name='bad', model=care_o_bot().build(), world=world)
