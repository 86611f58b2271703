# args: verify {case}
# exit: 2
# expect: is not a timedevent
"""A bad-input case: see tests/test_bad_inputs.py. A bare event in the timeline."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.model.events import ActionChange
scenario = Scenario(name='bad', model=care_o_bot().build(), timeline=(ActionChange('grasp'),))
