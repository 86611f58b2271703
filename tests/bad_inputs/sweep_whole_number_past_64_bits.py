# args: sweep {root}/scenarios/robot_day.py -p hand_memory=384,99999999999999999999 -o {tmp}/out.csv --no-progress
# exit: 2
# expect: -p hand_memory=99999999999999999999: a whole number a table holds lies within +-9.2e18
# untouched: {tmp}/out.csv
"""A bad-input case: see tests/test_bad_inputs.py. The scenario takes it, but the table's column cannot: every
run finished, then no table was written."""
