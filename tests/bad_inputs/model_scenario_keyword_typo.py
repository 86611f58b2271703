# args: verify {case}
# exit: 2
# expect: unknown keyword 'wrld'
# expect: did you mean 'world'
"""A bad-input case: see tests/test_bad_inputs.py. A misspelt Scenario field."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
scenario = Scenario(name='bad', model=care_o_bot().build(), wrld=None)
