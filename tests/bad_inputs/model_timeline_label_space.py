# args: explain {case} combined_slip_detector --at t3
# exit: 2
# expect: timeline label ' t3' begins or ends with a space: --at reads a comma-separated list of labels, each without its outer spaces, so it could never name this moment; write e.g. 't3'
"""A bad-input case: see tests/test_bad_inputs.py. --at strips the spaces around each label: no --at could name the moment."""
from desmon.model.cob3 import care_o_bot
from desmon.model.events import ActionChange
from desmon.model.scenario import Scenario, TimedEvent

scenario = Scenario(
    name="labels", model=care_o_bot().build(),
    timeline=(TimedEvent(0.0, ActionChange("grasp"), "start"), TimedEvent(2.0, ActionChange("release"), " t3")),
)
