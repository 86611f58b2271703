# args: replay {case}
# exit: 2
# expect: bad checker bounds
"""A bad-input case: see tests/test_bad_inputs.py. Bounds given as a dict with a misspelt field."""
from desmon.model.cob3 import care_o_bot
from desmon.model.events import ActionChange
from desmon.model.scenario import Scenario, TimedEvent

scenario = Scenario(
    name="dict", model=care_o_bot().build(), timeline=(TimedEvent(0.0, ActionChange("grasp")),),
    checker={"actions": ("grasp", "release"), "device": ("lwr_wrench",)},
)
