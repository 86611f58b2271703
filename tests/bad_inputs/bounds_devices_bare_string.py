# args: verify {case}
# exit: 2
# expect: devices = 'lwr_wrench' is a single string
# expect: letter by letter
"""A bad-input case: see tests/test_bad_inputs.py. A bare string where a tuple belongs."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.verify.bounds import Bounds, levels
scenario = Scenario(name='bad', model=care_o_bot().build(), checker=Bounds(actions=('grasp', 'hold'), devices='lwr_wrench'))
