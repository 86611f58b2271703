# args: explain {case} combined_slip_detector --at 5
# exit: 2
# expect: timeline label '5' reads as a time
"""A bad-input case: see tests/test_bad_inputs.py. --at 5 would silently mean the label, not t=5 s."""
from desmon.model.cob3 import care_o_bot
from desmon.model.events import ActionChange
from desmon.model.scenario import Scenario, TimedEvent

scenario = Scenario(
    name="labels", model=care_o_bot().build(),
    timeline=(TimedEvent(0.0, ActionChange("grasp"), "start"), TimedEvent(2.0, ActionChange("release"), "5")),
)
