# args: verify {case}
# exit: 2
# expect: deployment specification of 'combined_slip_detector' rebalances (min_gain 0.5) but has no preference to score platforms by
# expect: add a preference
"""A bad-input case: see tests/test_bad_inputs.py. rebalance with nothing to score by, in a specification built without the DSL."""
import dataclasses
from desmon.model.cob3 import care_o_bot
from desmon.model.requirements import Capacity, DeploymentSpec
from desmon.model.scenario import Scenario
model = care_o_bot(specs=False).build()
spec = DeploymentSpec('combined_slip_detector', (Capacity('memory', 250),), rebalance=0.5)
scenario = Scenario(name='bad', model=dataclasses.replace(model, specs=(spec,)))
