# args: verify {case}
# exit: 2
# expect: expected = ['holds'] is not a mapping
"""A bad-input case: see tests/test_bad_inputs.py. expected given a list."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
scenario = Scenario(name='bad', model=care_o_bot().build(), expected=['holds'])
