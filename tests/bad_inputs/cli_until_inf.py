# args: run {root}/scenarios/coffee_handover.py --until inf --no-progress
# exit: 2
# expect: --until must be a finite number of seconds, got inf
"""A bad-input case: see tests/test_bad_inputs.py."""
