# args: verify {root}/scenarios/coffee_handover.py -p N=4
# exit: 2
# expect: the scenario declares none (it does not call parameters(...))
"""A bad-input case: see tests/test_bad_inputs.py."""
