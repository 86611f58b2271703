# args: verify {root}/scenarios/two_detectors.py --json {tmp}/out.json --no-progress
# exit: 2
# expect: is a directory
# mkdir: {tmp}/out.json
"""A bad-input case: see tests/test_bad_inputs.py."""
