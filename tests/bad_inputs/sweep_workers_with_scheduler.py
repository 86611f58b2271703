# args: sweep {root}/scenarios/robot_day.py --scheduler tcp://127.0.0.1:8786 --workers 2 -o {tmp}/r.parquet
# exit: 2
# expect: --workers sets the size of the local cluster
# untouched: {tmp}/r.parquet
"""A bad-input case: see tests/test_bad_inputs.py."""
