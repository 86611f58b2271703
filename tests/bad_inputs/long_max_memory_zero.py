# args: verify {root}/scenarios/coffee_handover.py --max-memory 0
# exit: 2
# expect: --max-memory 0: give the memory budget
"""A bad-input case: see tests/test_bad_inputs.py."""
