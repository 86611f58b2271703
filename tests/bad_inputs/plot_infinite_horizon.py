# args: plot {data} -o {tmp}/t.png
# exit: 2
# expect: horizon inf is not a positive number
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py."""
