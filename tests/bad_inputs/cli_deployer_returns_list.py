# args: run {root}/scenarios/coffee_handover.py --deployer {case}:returns_list
# exit: 2
# expect: its reaction returned list, not a generator
"""A bad-input case: see tests/test_bad_inputs.py. A deployer object whose react returns a list."""
from desmon.deployment.deployer import Deployer

returns_list = Deployer("returns_list", "returns a list of commands instead of yielding them", lambda q, s, c, cc: [])
