# args: verify {case}
# exit: 2
# expect: initial = loadchange(
# expect: trailing comma
"""A bad-input case: see tests/test_bad_inputs.py. A one-item tuple without its comma."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.model.events import LoadChange
scenario = Scenario(name='bad', model=care_o_bot().build(), initial=(LoadChange('arm_pc', 300)))
