# args: sweep {root}/scenarios/robot_day.py -p hours=1,abc -o {tmp}/r.parquet
# exit: 2
# expect: -p hours=abc
# expect: finite number
# untouched: {tmp}/r.parquet
"""A bad-input case: see tests/test_bad_inputs.py."""
