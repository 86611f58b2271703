# args: verify {root}/scenarios/two_detectors.py --json {tmp}/no/such/out.json --no-progress
# exit: 2
# expect: --json {tmp}/no/such/out.json: directory {tmp}/no/such does not exist; create it
"""A bad-input case: see tests/test_bad_inputs.py."""
