# args: plot {data} -o {tmp}/t.png --from 1e400
# exit: 2
# expect: --from must be a finite time in seconds, 0 or more, got 1e400
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py."""
