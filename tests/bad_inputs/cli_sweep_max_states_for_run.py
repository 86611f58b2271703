# args: sweep {root}/scenarios/robot_day.py --max-states 10 -o {tmp}/x.csv
# exit: 2
# expect: --max-states applies to --job verify and analyze, not --job run; drop it
# untouched: {tmp}/x.csv
"""A bad-input case: see tests/test_bad_inputs.py. The refusal had named verify alone."""
