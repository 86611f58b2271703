# args: estimate {root}/scenarios/two_detectors.py --within tight
# exit: 2
# expect: --within must be a half-width
"""A bad-input case: see tests/test_bad_inputs.py. A precision that is no number."""
