# args: sweep {root}/scenarios/robot_day.py --task-timeout nan -o {tmp}/r.parquet
# exit: 2
# expect: --task-timeout must be a finite number
# untouched: {tmp}/r.parquet
"""A bad-input case: see tests/test_bad_inputs.py."""
