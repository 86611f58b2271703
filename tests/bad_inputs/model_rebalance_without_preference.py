# args: verify {case}
# exit: 2
# expect: has no preference to score platforms by
"""A bad-input case: see tests/test_bad_inputs.py. rebalance with nothing to score by."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario, TimedEvent
robot = care_o_bot(specs=False)
robot.depsl.deployment_specification('combined_slip_detector').add_constraint('capacity', 'memory', 250).rebalance(0.5)
scenario = Scenario(name='bad', model=robot.build())
