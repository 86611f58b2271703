# args: verify {root}/scenarios/coffee_handover.py --max-memory -5
# exit: 2
# expect: --max-memory -5: give the memory budget as a finite number of MB above 0
"""A bad-input case: see tests/test_bad_inputs.py."""
