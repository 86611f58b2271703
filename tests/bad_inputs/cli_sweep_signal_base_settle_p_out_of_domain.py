# args: sweep --job evaluate -p base_settle_p=5 --trials 3 --workers 1 -o {tmp}/e.csv
# exit: 2
# expect: -p base_settle_p=5: base_settle_p must be at most 1 (a probability)
# untouched: {tmp}/e.csv
"""A bad-input case: see tests/test_bad_inputs.py. A value the signal model cannot take is
refused before any run (a probability of 5 was accepted)."""
