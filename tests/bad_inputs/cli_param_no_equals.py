# args: verify {root}/scenarios/robot_day.py -p hours
# exit: 2
# expect: write -p NAME=VALUE
"""A bad-input case: see tests/test_bad_inputs.py."""
