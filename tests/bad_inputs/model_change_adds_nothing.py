# args: verify {case}
# exit: 2
# expect: adds and removes nothing
"""A bad-input case: see tests/test_bad_inputs.py. A requirement change with nothing in it."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario, TimedEvent
from desmon.model.events import RequirementChange
scenario = Scenario(name='bad', model=care_o_bot().build(), timeline=(TimedEvent(1.0, RequirementChange('combined_slip_detector')),))
