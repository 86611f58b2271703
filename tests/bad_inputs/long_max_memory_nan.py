# args: verify {root}/scenarios/coffee_handover.py --max-memory nan
# exit: 2
# expect: --max-memory must be a finite number of MB above 0, e.g. 2000, got nan
"""A bad-input case: see tests/test_bad_inputs.py."""
