# args: plot {data} -o {tmp}/t.png
# exit: 2
# expect: :2: a JSON int, not a record
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py."""
