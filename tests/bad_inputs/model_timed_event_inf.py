# args: verify {case}
# exit: 2
# expect: time of action grasp = inf is not finite
"""A bad-input case: see tests/test_bad_inputs.py. An event at t=inf."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.model.events import ActionChange
from desmon.model.scenario import TimedEvent
scenario = Scenario(name='bad', model=care_o_bot().build(), timeline=(TimedEvent(float('inf'), ActionChange('grasp')),))
