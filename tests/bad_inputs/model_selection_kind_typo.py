# args: verify {case}
# exit: 2
# expect: no device is of kind 'tactile_pda'
# expect: did you mean 'tactile_pad'
"""A bad-input case: see tests/test_bad_inputs.py. A Selection option of a kind no device has."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
robot = care_o_bot(specs=False)
robot.depsl.deployment_specification('tactile_slip_detector').add_constraint('selection', 'tactile_pda', 'force_sensor')
scenario = Scenario(name='bad', model=robot.build())
