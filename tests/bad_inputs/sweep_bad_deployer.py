# args: sweep {root}/scenarios/robot_day.py --deployer nope -o {tmp}/r.parquet
# exit: 2
# expect: nope
# untouched: {tmp}/r.parquet
"""A bad-input case: see tests/test_bad_inputs.py."""
