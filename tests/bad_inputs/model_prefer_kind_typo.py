# args: verify {case}
# exit: 2
# expect: unknown preference kind 'vendr'
# expect: did you mean 'vendor'
"""A bad-input case: see tests/test_bad_inputs.py. A misspelt preference kind."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario, TimedEvent
robot = care_o_bot(specs=False)
robot.depsl.deployment_specification('combined_slip_detector').prefer('vendr', 'tactile_pad', 'weiss')
scenario = Scenario(name='bad', model=robot.build())
