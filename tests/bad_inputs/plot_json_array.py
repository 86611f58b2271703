# args: plot {data} -o {tmp}/t.png
# exit: 2
# expect: a JSON array, not a record
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py."""
