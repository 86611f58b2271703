# args: run {case}
# exit: 2
# expect: the load steps of 'torso_pc' memory start at 800, but the scenario's initial 'load torso_pc memory=600' puts it at 600
"""A bad-input case: see tests/test_bad_inputs.py. The run had started the steps at 800, the
checker at the initial 600, and analyze refused the scenario: one written fact, three readings."""
from desmon.model.cob3 import care_o_bot
from desmon.model.events import LoadChange
from desmon.model.scenario import Scenario
from desmon.sim.world import LoadSteps, Step, World
world = World(task=(Step('grasp', 2.0), Step('hold', 28.0)), horizon=30.0,
              load_steps=(LoadSteps('torso_pc', levels=(600, 800), start=800, mean_interval=10.0),))
scenario = Scenario(name='bad', model=care_o_bot().build(), initial=(LoadChange('torso_pc', 600),), world=world)
