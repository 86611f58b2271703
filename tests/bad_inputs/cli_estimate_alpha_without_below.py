# args: estimate {root}/scenarios/two_detectors.py --alpha 0.01
# exit: 2
# expect: --alpha 0.01 sets an error probability of the threshold test: add --below X
"""A bad-input case: see tests/test_bad_inputs.py. A test's error probability without a test."""
