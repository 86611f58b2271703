# args: verify {case}
# exit: 2
# expect: checker bounds: unknown action 'stir'
# expect: or declare it with robot.action('stir'
"""A bad-input case: see tests/test_bad_inputs.py. Checker bounds naming an undeclared action."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.verify.bounds import Bounds
robot = care_o_bot()
robot.action('pour', risky=True, like='hold')
scenario = Scenario(name='bad', model=robot.build(), checker=Bounds(actions=('pour', 'stir')))
