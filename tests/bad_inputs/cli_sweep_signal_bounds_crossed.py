# args: sweep --job evaluate -p peak_lo=5 -p peak_hi=1 --trials 3 --workers 1 -o {tmp}/e.csv
# exit: 2
# expect: peak_lo must be at most peak_hi, 1.0 (the model draws between the two)
# untouched: {tmp}/e.csv
"""A bad-input case: see tests/test_bad_inputs.py. Each point failed with exit code 125, a bug's code."""
