# args: sweep {root}/scenarios/robot_day.py --job simulate -o {tmp}/r.parquet
# exit: 2
# expect: --job: invalid choice: 'simulate'
# untouched: {tmp}/r.parquet
"""A bad-input case: see tests/test_bad_inputs.py."""
