# args: verify {root}/scenarios/two_detectors.py --json {case}/out.json --no-progress
# exit: 2
# expect: is not a directory
"""A bad-input case: see tests/test_bad_inputs.py."""
