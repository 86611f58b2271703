# args: plot {data} -o {tmp}/t.png
# exit: 2
# expect: needs a finite numeric 't'
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py."""
