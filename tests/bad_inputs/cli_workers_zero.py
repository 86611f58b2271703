# args: verify {root}/scenarios/two_detectors.py --workers 0
# exit: 2
# expect: --workers must be positive (a whole number, 1 or more), got 0
"""A bad-input case: see tests/test_bad_inputs.py."""
