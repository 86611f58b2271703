# args: sweep {root}/scenarios/robot_day.py -p hand_memory=256,1.5 -o {tmp}/out.csv --no-progress
# exit: 2
# expect: -p hand_memory=1.5: hand_memory is a whole number
# untouched: {tmp}/out.csv
"""A bad-input case: see tests/test_bad_inputs.py. The list's 1.5 is the offender, not the 256 it made a decimal."""
