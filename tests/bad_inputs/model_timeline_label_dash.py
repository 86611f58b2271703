# args: explain {case} combined_slip_detector --at=-start
# exit: 2
# expect: timeline label '-start' begins with '-': the command line reads --at -start as another option
"""A bad-input case: see tests/test_bad_inputs.py. --at -start is read as another option, so no command could name it."""
from desmon.model.cob3 import care_o_bot
from desmon.model.events import ActionChange
from desmon.model.scenario import Scenario, TimedEvent

scenario = Scenario(
    name="labels", model=care_o_bot().build(),
    timeline=(TimedEvent(0.0, ActionChange("grasp"), "-start"), TimedEvent(2.0, ActionChange("release"), "t1")),
)
