# args: verify {case}
# exit: 2
# expect: weight = nan is not a number
"""A bad-input case: see tests/test_bad_inputs.py. A NaN preference weight."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario, TimedEvent
robot = care_o_bot(specs=False)
robot.depsl.deployment_specification('combined_slip_detector').prefer('spread', weight=float('nan'))
scenario = Scenario(name='bad', model=robot.build())
