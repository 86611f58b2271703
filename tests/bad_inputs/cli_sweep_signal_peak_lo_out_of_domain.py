# args: sweep --job evaluate -p peak_lo=0 --trials 3 --workers 1 -o {tmp}/e.csv
# exit: 2
# expect: -p peak_lo=0: peak_lo must be above 0
# untouched: {tmp}/e.csv
"""A bad-input case: see tests/test_bad_inputs.py. A value the signal model cannot take is
refused before any run (a log-uniform draw between peak_lo and peak_hi: 0 had ended every row in a math domain error (exit 125))."""
