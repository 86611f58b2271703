# args: verify {case}
# exit: 2
# expect: load on 'arm_pc' memory = inf is not finite
"""A bad-input case: see tests/test_bad_inputs.py. An infinite load."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.model.events import LoadChange
scenario = Scenario(name='bad', model=care_o_bot().build(), initial=(LoadChange('arm_pc', float('inf')),))
