# args: sweep {root}/scenarios/robot_day.py --job evaluate -p noise_counts=2,4 -o {tmp}/r.parquet
# exit: 2
# expect: reads no scenario
# untouched: {tmp}/r.parquet
"""A bad-input case: see tests/test_bad_inputs.py."""
