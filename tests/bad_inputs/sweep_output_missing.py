# args: sweep {root}/scenarios/robot_day.py -p hours=1
# exit: 2
# expect: the following arguments are required: -o/--output
"""A bad-input case: see tests/test_bad_inputs.py."""
