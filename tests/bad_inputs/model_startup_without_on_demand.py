# args: verify {case}
# exit: 2
# expect: startup_s = 20 but is not on_demand
"""A bad-input case: see tests/test_bad_inputs.py. A start-up delay on a platform that is always there."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario, TimedEvent
robot = care_o_bot(specs=False)
robot.platform('edge', memory=2048, startup_s=20)
scenario = Scenario(name='bad', model=robot.build())
