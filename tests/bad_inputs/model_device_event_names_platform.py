# args: verify {case}
# exit: 2
# expect: 'arm_pc' is a platform
# expect: platformdown
"""A bad-input case: see tests/test_bad_inputs.py. DeviceFail of a platform name."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.model.events import DeviceFail
scenario = Scenario(name='bad', model=care_o_bot().build(), initial=(DeviceFail('arm_pc'),))
