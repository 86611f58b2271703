# args: sweep {root}/scenarios/robot_day.py -p hours=0.02 --resume -o {tmp}/r.csv
# copy: {data} {tmp}/r.csv
# exit: 2
# expect: was made with --job verify, not run
# untouched: {tmp}/r.csv
"""A bad-input case: see tests/test_bad_inputs.py."""
