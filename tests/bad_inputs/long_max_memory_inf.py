# args: verify {root}/scenarios/coffee_handover.py --max-memory inf
# exit: 2
# expect: --max-memory must be a finite number of MB above 0, e.g. 2000, got inf
"""A bad-input case: see tests/test_bad_inputs.py."""
