# args: verify {root}/scenarios/two_detectors.py --workers 100000 --no-progress
# exit: 2
# expect: --workers must be at most
# expect: (4 per CPU here), got 100000
"""A bad-input case: see tests/test_bad_inputs.py. Thousands of forked workers would exhaust the machine."""
