# args: verify {root}/scenarios/coffee_handover.py --max-memory lots
# exit: 2
# expect: argument --max-memory: invalid float value: 'lots'
"""A bad-input case: see tests/test_bad_inputs.py."""
