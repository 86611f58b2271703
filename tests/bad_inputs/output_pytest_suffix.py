# args: verify {root}/scenarios/two_detectors.py --pytest {tmp}/test_cex --no-progress
# exit: 2
# expect: must end in .py
# untouched: {tmp}/test_cex
"""A bad-input case: see tests/test_bad_inputs.py."""
