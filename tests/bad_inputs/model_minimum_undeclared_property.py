# args: verify {case}
# exit: 2
# expect: no platform declares a property 'link_latency'
# expect: did you mean 'link_latency_ms'
"""A bad-input case: see tests/test_bad_inputs.py. A Maximum on a property no platform declares."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
robot = care_o_bot(specs=False)
robot.depsl.deployment_specification('force_slip_detector').add_constraint('maximum', 'link_latency', 2)
scenario = Scenario(name='bad', model=robot.build())
