# args: verify {root}/scenarios/coffee_handover.py --max-memory lots
# exit: 2
# expect: --max-memory must be a memory budget in MB, e.g. 2000, got 'lots'
"""A bad-input case: see tests/test_bad_inputs.py."""
