# args: sweep --job evaluate -p noise_counts=nan --trials 3 --workers 1 -o {tmp}/e.csv
# exit: 2
# expect: noise_counts must be a finite number
# untouched: {tmp}/e.csv
"""A bad-input case: see tests/test_bad_inputs.py. NaN and inf gave rows of real-looking figures."""
