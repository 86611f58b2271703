# args: verify {case}
# exit: 2
# expect: system model platforms=(): a model needs at least one platform for the monitors to run on
"""A bad-input case: see tests/test_bad_inputs.py. A model without any platform (it used to load, then crash verify)."""
from desmon.model.system import SystemModel
from desmon.model.scenario import Scenario

scenario = Scenario("no_platform", SystemModel(platforms=()))
