# args: verify {root}/scenarios/two_detectors.py --timeout nan
# exit: 2
# expect: --timeout must be a finite number of seconds, got nan
"""A bad-input case: see tests/test_bad_inputs.py."""
