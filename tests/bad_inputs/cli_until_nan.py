# args: run {root}/scenarios/coffee_handover.py --until nan --no-progress
# exit: 2
# expect: --until must be a finite number of seconds, got nan
"""A bad-input case: see tests/test_bad_inputs.py."""
