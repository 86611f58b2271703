# args: verify {case}
# exit: 2
# expect: unknown invariant 'fixd'
# expect: did you mean 'fixed'
"""A bad-input case: see tests/test_bad_inputs.py. A misspelt invariant name."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.verify.bounds import Bounds, levels
scenario = Scenario(name='bad', model=care_o_bot().build(), checker=Bounds(actions=('grasp', 'hold'), instantaneous=('fixd',)))
