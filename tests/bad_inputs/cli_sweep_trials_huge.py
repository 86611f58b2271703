# args: sweep --job evaluate --trials 99999999999999999999 -o {tmp}/e.csv
# exit: 2
# expect: --trials must be at most 1,000,000
# untouched: {tmp}/e.csv
"""A bad-input case: see tests/test_bad_inputs.py. Each row failed on its own, after the cluster started."""
