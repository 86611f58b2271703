# copy: {data} {tmp}/e.csv
# args: sweep {root}/scenarios/robot_day.py -p hours=0.05 --until 60 --seeds 2 --workers 1 --no-progress --resume -o {tmp}/e.csv
# exit: 2
# expect: is not a desmon sweep table (no column point
# untouched: {tmp}/e.csv
"""A bad-input case: see tests/test_bad_inputs.py. A table of no rows was taken for an empty sweep and replaced."""
