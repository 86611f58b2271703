# args: verify {case}
# exit: 2
# expect: on_demand = 'yes' is not true or false
"""A bad-input case: see tests/test_bad_inputs.py. on_demand given as text."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario, TimedEvent
robot = care_o_bot(specs=False)
robot.platform('edge', memory=2048, on_demand='yes')
scenario = Scenario(name='bad', model=robot.build())
