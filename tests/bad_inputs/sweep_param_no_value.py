# args: sweep {root}/scenarios/robot_day.py -p hours -o {tmp}/r.parquet
# exit: 2
# expect: -p NAME=V1,V2
# untouched: {tmp}/r.parquet
"""A bad-input case: see tests/test_bad_inputs.py."""
