# args: verify {case}
# exit: 2
# expect: both actions=('hold', 'grasp', 'release') and task are given
"""A bad-input case: see tests/test_bad_inputs.py. actions would be silently ignored beside a task."""
from desmon.model import GRASP, HOLD, RELEASE
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.verify.bounds import Bounds

scenario = Scenario(
    name="both",
    model=care_o_bot().build(),
    checker=Bounds(actions=(HOLD, GRASP, RELEASE), task={HOLD: (GRASP,), GRASP: (HOLD,)}, initial_action=HOLD),
)
