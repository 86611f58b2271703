# args: verify {case}
# exit: 2
# expect: preference 'most_free' got 0 argument(s)
# expect: ('most_free', resource
"""A bad-input case: see tests/test_bad_inputs.py. most_free without the resource it scores."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario, TimedEvent
robot = care_o_bot(specs=False)
robot.depsl.deployment_specification('combined_slip_detector').prefer('most_free')
scenario = Scenario(name='bad', model=robot.build())
