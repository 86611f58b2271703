# args: verify {case}
# exit: 2
# expect: start_failures = 1.5 is not a whole number
"""A bad-input case: see tests/test_bad_inputs.py. A fractional bound."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.verify.bounds import Bounds, levels
scenario = Scenario(name='bad', model=care_o_bot().build(), checker=Bounds(actions=('grasp', 'hold'), start_failures=1.5))
