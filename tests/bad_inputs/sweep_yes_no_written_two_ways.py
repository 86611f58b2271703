# args: sweep {root}/scenarios/coffee_shift.py -p faults=1,true -o {tmp}/out.csv --no-progress
# exit: 2
# expect: -p faults: values 1 and true are the same yes/no value; list each value once
# untouched: {tmp}/out.csv
"""A bad-input case: see tests/test_bad_inputs.py. 1 and true are one setting of a yes/no parameter: two points
of the same setting, under different seeds, labelled as two."""
