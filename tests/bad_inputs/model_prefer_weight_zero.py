# args: verify {case}
# exit: 2
# expect: weight = 0 is not positive
"""A bad-input case: see tests/test_bad_inputs.py. A zero preference weight (it would score nothing)."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario, TimedEvent
robot = care_o_bot(specs=False)
robot.depsl.deployment_specification('combined_slip_detector').prefer('spread', weight=0)
scenario = Scenario(name='bad', model=robot.build())
