# args: verify {tmp}/nosuch.py --json {tmp}/out.json
# exit: 2
# expect: no such scenario file
# untouched: {tmp}/out.json
"""A bad-input case: see tests/test_bad_inputs.py."""
