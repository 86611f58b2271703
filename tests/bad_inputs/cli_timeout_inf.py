# args: verify {root}/scenarios/two_detectors.py --timeout inf
# exit: 2
# expect: --timeout must be a finite number of seconds, got inf
"""A bad-input case: see tests/test_bad_inputs.py."""
