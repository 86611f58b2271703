# args: verify {case}
# exit: 2
# expect: no platform declares a 'memroy' capacity
# expect: did you mean 'memory'
"""A bad-input case: see tests/test_bad_inputs.py. A preference scoring a capacity no platform has."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario, TimedEvent
robot = care_o_bot(specs=False)
robot.depsl.deployment_specification('combined_slip_detector').prefer('most_free', 'memroy')
scenario = Scenario(name='bad', model=robot.build())
