# args: run {root}/scenarios/robot_day.py -p hand_memory=3.5e2
# exit: 2
# expect: hand_memory is a whole number (default 384)
"""A bad-input case: see tests/test_bad_inputs.py."""
