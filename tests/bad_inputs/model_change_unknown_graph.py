# args: verify {case}
# exit: 2
# expect: names graph 'combined' with no deployment specification
# expect: specifications: force_slip_detector, tactile_slip_detector, combined_slip_detector
"""A bad-input case: see tests/test_bad_inputs.py. A requirement change on a graph that does not exist."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario, TimedEvent
from desmon.model.events import RequirementChange
from desmon.model.requirements import Capacity
scenario = Scenario(name='bad', model=care_o_bot().build(), timeline=(TimedEvent(1.0, RequirementChange('combined', add=(Capacity('memory', 350),))),))
