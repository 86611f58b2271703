# args: sweep {root}/scenarios/robot_day.py --examples 5 -o {tmp}/r.parquet
# exit: 2
# expect: --examples applies to --job fuzz, not --job run
# untouched: {tmp}/r.parquet
"""A bad-input case: see tests/test_bad_inputs.py."""
