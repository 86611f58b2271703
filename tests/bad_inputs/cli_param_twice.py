# args: verify {root}/scenarios/robot_day.py -p hours=1 -p hours=2
# exit: 2
# expect: -p hours is given twice
"""A bad-input case: see tests/test_bad_inputs.py."""
