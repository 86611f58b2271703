# args: plot {tmp}/run.png -o {tmp}/run.png
# exit: 2
# expect: is the input file being read
# copy: {data} {tmp}/run.png
# untouched: {tmp}/run.png
"""A bad-input case: see tests/test_bad_inputs.py."""
