# args: verify {root}/scenarios/two_detectors.py --timeout -1
# exit: 2
# expect: --timeout must be positive (seconds above 0), got -1
"""A bad-input case: see tests/test_bad_inputs.py."""
