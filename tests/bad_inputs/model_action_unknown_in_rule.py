# args: verify {case}
# exit: 2
# expect: rules: unknown action context 'pur' (did you mean 'pour'?)
# expect: or declare it with robot.action('pur'
"""A bad-input case: see tests/test_bad_inputs.py. A rule for an action the model neither has built in nor declares."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
robot = care_o_bot(rules=False)
robot.action('pour', risky=True, like='hold')
robot.rules({'pur': 'force_slip_detector'})
scenario = Scenario(name='bad', model=robot.build())
