# args: verify {case}
# exit: 2
# expect: rebalance min_gain of 'combined_slip_detector' = -1 is negative
"""A bad-input case: see tests/test_bad_inputs.py. A negative rebalancing threshold."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario, TimedEvent
robot = care_o_bot(specs=False)
robot.depsl.deployment_specification('combined_slip_detector').prefer('spread').rebalance(-1)
scenario = Scenario(name='bad', model=robot.build())
