# args: verify {case}
# exit: 2
# expect: loads move 'cpu' on 'torso_pc', which has no such capacity
"""A bad-input case: see tests/test_bad_inputs.py. Loads on a resource the platform lacks."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.verify.bounds import Bounds, levels
scenario = Scenario(name='bad', model=care_o_bot().build(), checker=Bounds(actions=('grasp', 'hold'), loads={'torso_pc': (0, 100)}, load_resource='cpu'))
