# args: evaluate --trials 0
# exit: 2
# expect: --trials must be positive (a whole number, 1 or more), got 0
"""A bad-input case: see tests/test_bad_inputs.py."""
