# args: sweep {root}/scenarios/robot_day.py -p hours=1,,2 -o {tmp}/r.parquet
# exit: 2
# expect: empty value
# untouched: {tmp}/r.parquet
"""A bad-input case: see tests/test_bad_inputs.py."""
