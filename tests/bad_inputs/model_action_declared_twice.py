# args: verify {case}
# exit: 2
# expect: action 'pour' is declared twice
"""A bad-input case: see tests/test_bad_inputs.py. The same action declared twice."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
robot = care_o_bot()
robot.action('pour', risky=True, like='hold')
robot.action('pour', risky=False)
scenario = Scenario(name='bad', model=robot.build())
