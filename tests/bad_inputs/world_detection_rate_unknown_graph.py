# args: analyze {case}
# exit: 2
# expect: detection_rates names 'camera_detector'
# expect: which is no perception graph of the model: give the rate of one without a signal model (the model has none)
"""A bad-input case: see tests/test_bad_inputs.py. A detection rate for a graph the model does not have (a typo)."""
from desmon.model.cob3 import care_o_bot
from desmon.model.scenario import Scenario
from desmon.sim.world import Step, World

scenario = Scenario(name='bad', model=care_o_bot().build(), world=World(task=(Step('grasp', 2.0), Step('hold', 8.0)), horizon=10.0, detection_rates={'camera_detector': 0.9}))
