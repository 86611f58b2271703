# args: replay {case}
# exit: 2
# expect: leaves 'force_slip_detector' with two Capacity requirements on 'memory': a graph consumes one amount of a resource; remove the one it has in the same change
"""A bad-input case: see tests/test_bad_inputs.py."""
from desmon.model.cob3 import care_o_bot
from desmon.model.events import ActionChange, RequirementChange
from desmon.model.requirements import Capacity
from desmon.model.scenario import Scenario, TimedEvent

scenario = Scenario(
    name="change", model=care_o_bot().build(),
    timeline=(TimedEvent(0.0, ActionChange("release"), "t0"), TimedEvent(2.0, RequirementChange("force_slip_detector", add=(Capacity("memory", 80),)), "t1")),
)
