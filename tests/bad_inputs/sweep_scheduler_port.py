# args: sweep {root}/scenarios/robot_day.py --scheduler tcp://localhost:99999 -o {tmp}/r.parquet
# exit: 2
# expect: tcp://HOST:PORT
# untouched: {tmp}/r.parquet
"""A bad-input case: see tests/test_bad_inputs.py."""
