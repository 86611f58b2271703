# args: verify {case}
# exit: 2
# expect: max_failures = nan is not a number
"""A bad-input case: see tests/test_bad_inputs.py. A NaN bound."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.verify.bounds import Bounds, levels
scenario = Scenario(name='bad', model=care_o_bot().build(), checker=Bounds(actions=('grasp', 'hold'), max_failures=float('nan')))
