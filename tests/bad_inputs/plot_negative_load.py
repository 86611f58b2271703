# args: plot {data} -o {tmp}/t.png
# exit: 2
# expect: amount -5 is not a finite number >= 0
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py."""
