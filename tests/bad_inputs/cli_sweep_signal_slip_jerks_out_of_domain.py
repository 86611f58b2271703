# args: sweep --job evaluate -p slip_jerks=0,3 --trials 3 --workers 1 -o {tmp}/e.csv
# exit: 2
# expect: -p slip_jerks=0: slip_jerks must be a whole number of jerks, 1 or more
# untouched: {tmp}/e.csv
"""A bad-input case: see tests/test_bad_inputs.py. A value the signal model cannot take is
refused before any run (0 jerks divided by zero: rates of 0.0 and exit 0)."""
