# args: verify {case}
# exit: 2
# expect: unknown keyword 'device'
# expect: did you mean 'devices'
"""A bad-input case: see tests/test_bad_inputs.py. A misspelt Bounds field."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.verify.bounds import Bounds, levels
scenario = Scenario(name='bad', model=care_o_bot().build(), checker=Bounds(actions=('grasp', 'hold'), device=('lwr_wrench',)))
