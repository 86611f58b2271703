# args: sweep {root}/scenarios/robot_day.py -o {tmp}/r.xlsx
# exit: 2
# expect: must end in .parquet or .csv
# untouched: {tmp}/r.xlsx
"""A bad-input case: see tests/test_bad_inputs.py."""
