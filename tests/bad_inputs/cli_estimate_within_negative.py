# args: estimate {root}/scenarios/two_detectors.py --within -1
# exit: 2
# expect: --within must be a positive half-width
# expect: (1%)
"""A bad-input case: see tests/test_bad_inputs.py. A negative precision: one line naming --within and both forms."""
