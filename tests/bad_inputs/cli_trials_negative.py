# args: evaluate --trials -5
# exit: 2
# expect: --trials must be positive (a whole number, 1 or more), got -5
"""A bad-input case: see tests/test_bad_inputs.py."""
