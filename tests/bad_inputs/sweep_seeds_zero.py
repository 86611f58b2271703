# args: sweep {root}/scenarios/robot_day.py --seeds 0 -o {tmp}/r.parquet
# exit: 2
# expect: --seeds must be positive
# untouched: {tmp}/r.parquet
"""A bad-input case: see tests/test_bad_inputs.py."""
