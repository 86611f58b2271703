# args: plot {data} -o {tmp}/t.png
# exit: 2
# expect: no 'end' record after 2 records (the last at t=0 s): the trace is cut short
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py."""
