# args: plot {data} -o {tmp}/t.png --from nan
# exit: 2
# expect: --from must be a finite time in seconds, 0 or more, got nan
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py."""
