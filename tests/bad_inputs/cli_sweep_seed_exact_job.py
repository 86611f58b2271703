# args: sweep {root}/scenarios/coffee_handover.py --job verify --seed 5 -o {tmp}/v.csv
# exit: 2
# expect: --seed 5 with --job verify
# untouched: {tmp}/v.csv
"""A bad-input case: see tests/test_bad_inputs.py. The check uses no seed: the seed would only rename the rows."""
