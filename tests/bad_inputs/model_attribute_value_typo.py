# args: verify {case}
# exit: 2
# expect: no platform has os = 'linx'
# expect: did you mean 'linux'
"""A bad-input case: see tests/test_bad_inputs.py. An Attribute value no platform has."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
robot = care_o_bot(specs=False)
robot.depsl.deployment_specification('force_slip_detector').add_constraint('attribute', 'os', 'linx')
scenario = Scenario(name='bad', model=robot.build())
