# args: replay {case}
# exit: 2
# expect: TimedEvent(...): unknown keyword 'evnt' (did you mean 'event'?); it takes (time, event, label='')
"""A bad-input case: see tests/test_bad_inputs.py."""
from desmon.model.cob3 import care_o_bot
from desmon.model.events import ActionChange
from desmon.model.scenario import Scenario, TimedEvent

scenario = Scenario(name="te", model=care_o_bot().build(), timeline=(TimedEvent(1.0, evnt=ActionChange("grasp")),))
