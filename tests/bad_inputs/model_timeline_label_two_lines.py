# args: replay {case}
# exit: 2
# expect: of action grasp at t=1 is not one line of printable text: write e.g. 't1'
"""A bad-input case: see tests/test_bad_inputs.py. The newline forged a line of the replay's report."""
from desmon.model.cob3 import care_o_bot
from desmon.model.events import ActionChange
from desmon.model.scenario import Scenario, TimedEvent

scenario = Scenario(name="te", model=care_o_bot().build(), timeline=(TimedEvent(1.0, ActionChange("grasp"), "t1\nt9 t=99s  action hold"),))
