# args: run {case} --no-progress
# exit: 2
# expect: unknown task action 'poor' (did you mean 'pour'?)
"""A bad-input case: see tests/test_bad_inputs.py. A world task step naming an undeclared action."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.sim.world import Step, World
robot = care_o_bot()
robot.action('pour', risky=True, like='hold')
scenario = Scenario(name='bad', model=robot.build(), world=World(task=(Step('grasp', 2.0), Step('poor', 5.0)), horizon=7.0))
