# args: verify {root}/scenarios/two_detectors.py --json {tmp}/out.txt --no-progress
# exit: 2
# expect: must end in .json
# untouched: {tmp}/out.txt
"""A bad-input case: see tests/test_bad_inputs.py."""
