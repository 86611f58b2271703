# args: plot {data} -o {tmp}/t.png --from -1
# exit: 2
# expect: --from -1: give a time in seconds, 0 or more
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py."""
