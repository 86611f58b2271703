# args: sweep {root}/scenarios/robot_day.py --scheduler localhost:8786 -o {tmp}/r.parquet
# exit: 2
# expect: give the address of a running Dask scheduler, tcp://HOST:PORT
# untouched: {tmp}/r.parquet
"""A bad-input case: see tests/test_bad_inputs.py."""
