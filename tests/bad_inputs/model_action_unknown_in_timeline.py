# args: replay {case}
# exit: 2
# expect: unknown action 'wpie' (did you mean 'wipe'?)
"""A bad-input case: see tests/test_bad_inputs.py. An ActionChange naming an undeclared action."""
from desmon.model.cob3 import care_o_bot
from desmon.model.events import ActionChange
from desmon.model.scenario import Scenario, TimedEvent
robot = care_o_bot()
robot.action('wipe', risky=False)
scenario = Scenario(name='bad', model=robot.build(), timeline=(TimedEvent(0.0, ActionChange('wpie')),))
