# args: verify {case}
# exit: 2
# expect: no tactile_pad device is made by 'wiess'
# expect: did you mean 'weiss'
# expect: can never hold
"""A bad-input case: see tests/test_bad_inputs.py. A kind@vendor option that can never hold."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
robot = care_o_bot(specs=False)
robot.depsl.deployment_specification('tactile_slip_detector').add_constraint('selection', 'tactile_pad@wiess', 'force_sensor')
scenario = Scenario(name='bad', model=robot.build())
