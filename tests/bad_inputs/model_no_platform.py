# args: verify {case}
# exit: 2
# expect: scenario 'no_platform': its model has no platform (SystemModel(platforms=())), so no monitor can run and there is nothing to check
"""A bad-input case: see tests/test_bad_inputs.py. A model without any platform (it used to load, then crash verify)."""
from desmon.model.system import SystemModel
from desmon.model.scenario import Scenario

scenario = Scenario("no_platform", SystemModel(platforms=()))
