# args: verify {case}
# exit: 2
# expect: removes capacity(memory >= 300 mb), which 'combined_slip_detector' never has
"""A bad-input case: see tests/test_bad_inputs.py. A requirement change removing what the specification never had."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario, TimedEvent
from desmon.model.events import RequirementChange
from desmon.model.requirements import Capacity
scenario = Scenario(name='bad', model=care_o_bot().build(), timeline=(TimedEvent(1.0, RequirementChange('combined_slip_detector', add=(Capacity('memory', 350),), remove=(Capacity('memory', 300),))),))
