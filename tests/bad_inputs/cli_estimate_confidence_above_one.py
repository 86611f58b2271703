# args: estimate {root}/scenarios/two_detectors.py --confidence 1.5
# exit: 2
# expect: --confidence must be a confidence strictly between 0 and 1
# expect: 0.99
"""A bad-input case: see tests/test_bad_inputs.py. A confidence of 150 %."""
