# args: verify {root}/scenarios/coffee_handover.py --max-memory inf
# exit: 2
# expect: --max-memory inf: give the memory budget
"""A bad-input case: see tests/test_bad_inputs.py."""
