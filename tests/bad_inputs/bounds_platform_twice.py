# args: verify {case}
# exit: 2
# expect: platforms list 'arm_pc' twice
"""A bad-input case: see tests/test_bad_inputs.py. A copy-pasted platform in the bounds."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.verify.bounds import Bounds
scenario = Scenario(name='bad', model=care_o_bot().build(), checker=Bounds(actions=('grasp', 'hold'), platforms=('arm_pc', 'hand_pc', 'arm_pc')))
