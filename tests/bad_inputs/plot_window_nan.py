# args: plot {data} -o {tmp}/t.png --from nan
# exit: 2
# expect: --from nan: give a time in seconds
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py."""
