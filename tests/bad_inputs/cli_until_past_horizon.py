# args: run {root}/scenarios/coffee_handover.py --until 1000 --no-progress
# exit: 2
# expect: the scenario's task ends at its horizon of 28 s
"""A bad-input case: see tests/test_bad_inputs.py."""
