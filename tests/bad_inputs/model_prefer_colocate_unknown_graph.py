# args: verify {case}
# exit: 2
# expect: there is no perception graph 'force_slip'
"""A bad-input case: see tests/test_bad_inputs.py. colocate with a graph that does not exist."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario, TimedEvent
robot = care_o_bot(specs=False)
robot.depsl.deployment_specification('combined_slip_detector').prefer('colocate', 'force_slip')
scenario = Scenario(name='bad', model=robot.build())
