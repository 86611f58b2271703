# args: verify {case}
# exit: 2
# expect: the search starts in 'hold' (the timeline's first ActionChange; no initial_action given), which has no entry in the task, so the robot would never move
"""A bad-input case: see tests/test_bad_inputs.py. It HELD in 2 states: none of the task was explored."""
from desmon.model.cob3 import care_o_bot
from desmon.model.events import ActionChange
from desmon.model.scenario import Scenario, TimedEvent
from desmon.verify.bounds import Bounds

scenario = Scenario(
    name="task_init", model=care_o_bot().build(),
    timeline=(TimedEvent(0.0, ActionChange("hold"), "t0"),),
    checker=Bounds(task={"idle": ("grasp",), "grasp": ("move_base",), "move_base": ("release",), "release": ("idle",)}, devices=("lwr_wrench",)),
)
