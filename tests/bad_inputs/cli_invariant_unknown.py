# args: verify {root}/scenarios/two_detectors.py --invariant nosuch --no-progress
# exit: 2
# expect: unknown invariant 'nosuch'
"""A bad-input case: see tests/test_bad_inputs.py."""
