# args: verify {case}
# exit: 2
# expect: platform 'torso_pc' is not on demand
# expect: on_demand=true
"""A bad-input case: see tests/test_bad_inputs.py. A join of a platform that is always there."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario, TimedEvent
from desmon.model.events import PlatformJoin
scenario = Scenario(name='bad', model=care_o_bot().build(), timeline=(TimedEvent(1.0, PlatformJoin('torso_pc')),))
