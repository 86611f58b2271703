# args: fuzz {root}/scenarios/coffee_handover.py --examples 99999999999999999999
# exit: 2
# expect: --examples must be at most 1,000,000 sequences
"""A bad-input case: see tests/test_bad_inputs.py. Accepted, it would generate sequences for ever."""
