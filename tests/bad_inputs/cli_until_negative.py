# args: run {root}/scenarios/coffee_handover.py --until -1 --no-progress
# exit: 2
# expect: --until must be positive (seconds above 0), got -1
"""A bad-input case: see tests/test_bad_inputs.py."""
