# args: fuzz {root}/scenarios/coffee_handover.py --seed -1
# exit: 2
# expect: --seed must be 0 or more (a whole number), got -1
"""A bad-input case: see tests/test_bad_inputs.py."""
