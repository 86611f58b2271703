# args: verify {case}
# exit: 2
# expect: task moves from 'grasp' to 'hold', which has no entry
"""A bad-input case: see tests/test_bad_inputs.py. A task that silently stops."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.verify.bounds import Bounds, levels
scenario = Scenario(name='bad', model=care_o_bot().build(), checker=Bounds(task={'idle': ('grasp',), 'grasp': ('hold',)}))
