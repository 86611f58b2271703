# args: plot {data} -o {tmp}/t.png
# exit: 2
# expect: does not start with a 'run' record
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py."""
