# args: sweep --job evaluate -p tactile_rate=0 --trials 3 --workers 1 -o {tmp}/e.csv
# exit: 2
# expect: tactile_rate must be above 0
# untouched: {tmp}/e.csv
"""A bad-input case: see tests/test_bad_inputs.py. A rate of 0 divided by zero and gave rows of figures."""
