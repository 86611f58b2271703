# args: verify {root}/scenarios/two_detectors.py --max-depth -1
# exit: 2
# expect: --max-depth must be positive (a whole number, 1 or more), got -1
"""A bad-input case: see tests/test_bad_inputs.py."""
