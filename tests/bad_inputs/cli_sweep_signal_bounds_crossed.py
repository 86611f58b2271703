# args: sweep --job evaluate -p peak_lo=5 -p peak_hi=1 --trials 3 --workers 1 -o {tmp}/e.csv
# exit: 2
# expect: peak_lo 5 above peak_hi 1
# untouched: {tmp}/e.csv
"""A bad-input case: see tests/test_bad_inputs.py. Each point failed with exit code 125, a bug's code."""
