# args: show {case} --at t3,x --format dot
# exit: 2
# expect: timeline label 't3,x' holds a comma: --at reads a comma-separated list
"""A bad-input case: see tests/test_bad_inputs.py. --at splits its list at commas: no --at could name the moment."""
from desmon.model.cob3 import care_o_bot
from desmon.model.events import ActionChange
from desmon.model.scenario import Scenario, TimedEvent

scenario = Scenario(
    name="labels", model=care_o_bot().build(),
    timeline=(TimedEvent(0.0, ActionChange("grasp"), "start"), TimedEvent(2.0, ActionChange("release"), "t3,x")),
)
