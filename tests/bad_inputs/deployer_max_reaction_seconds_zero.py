# args: run {root}/scenarios/coffee_handover.py --max-reaction-seconds 0
# exit: 2
# expect: --max-reaction-seconds
"""A bad-input case: see tests/test_bad_inputs.py."""
