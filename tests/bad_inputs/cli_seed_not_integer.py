# args: run {root}/scenarios/coffee_handover.py --seed 1.5
# exit: 2
# expect: --seed must be a whole number, got '1.5'
"""A bad-input case: see tests/test_bad_inputs.py."""
