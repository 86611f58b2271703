# args: run {case} --no-progress
# exit: 2
# expect: DeviceFail device 'pad\x00' contains '\x00' (U+0000)
"""A bad-input case: see tests/test_bad_inputs.py. An event naming a device with a NUL byte: events name things by the
same rule as the model."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.model.events import DeviceFail
scenario = Scenario(name='bad', model=care_o_bot().build(), initial=(DeviceFail('pad\x00'),))
