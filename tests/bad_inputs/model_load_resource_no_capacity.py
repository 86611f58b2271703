# args: verify {case}
# exit: 2
# expect: platform 'arm_pc' has no 'cpu' capacity
"""A bad-input case: see tests/test_bad_inputs.py. A load on a resource the platform does not have."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.model.events import LoadChange
scenario = Scenario(name='bad', model=care_o_bot().build(), initial=(LoadChange('arm_pc', 50, 'cpu'),))
