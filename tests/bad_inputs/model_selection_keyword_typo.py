# args: verify {case}
# exit: 2
# expect: unknown keyword 'atleast'
# expect: did you mean 'at_least'
"""A bad-input case: see tests/test_bad_inputs.py. A misspelt keyword used to be dropped silently (at_least stayed 1)."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
robot = care_o_bot(specs=False)
robot.depsl.deployment_specification('tactile_slip_detector').add_constraint('selection', 'tactile_pad@weiss', 'force_sensor', atleast=2)
scenario = Scenario(name='bad', model=robot.build())
