# args: verify {case}
# exit: 2
# expect: are not in rising order ([0, 200, 100])
"""A bad-input case: see tests/test_bad_inputs.py. The load would step 0 -> 200 -> 100."""
from desmon.model.cob3 import LOADS, care_o_bot
from desmon.model.events import LoadChange
from desmon.model.scenario import Scenario
from desmon.verify.bounds import Bounds

scenario = Scenario(
    name="unsorted", model=care_o_bot().build(), initial=tuple(LoadChange(p, 0) for p in LOADS),
    checker=Bounds(actions=("grasp", "release"), loads={"torso_pc": (0, 200, 100)}),
)
