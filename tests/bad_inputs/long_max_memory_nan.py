# args: verify {root}/scenarios/coffee_handover.py --max-memory nan
# exit: 2
# expect: --max-memory nan: give the memory budget
"""A bad-input case: see tests/test_bad_inputs.py."""
