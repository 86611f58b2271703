# args: verify {case}
# exit: 2
# expect: task successors of 'idle' = 'grasp' is a single string
"""A bad-input case: see tests/test_bad_inputs.py. A bare string successor."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.verify.bounds import Bounds, levels
scenario = Scenario(name='bad', model=care_o_bot().build(), checker=Bounds(task={'idle': 'grasp', 'grasp': ('idle',)}))
