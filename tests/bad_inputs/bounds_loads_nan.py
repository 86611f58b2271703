# args: verify {case}
# exit: 2
# expect: load level of 'torso_pc' = nan is not a number
"""A bad-input case: see tests/test_bad_inputs.py. A NaN load level."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.verify.bounds import Bounds, levels
scenario = Scenario(name='bad', model=care_o_bot().build(), checker=Bounds(actions=('grasp', 'hold'), loads={'torso_pc': (0, float('nan'))}))
