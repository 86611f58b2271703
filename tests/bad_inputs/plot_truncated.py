# args: plot {data} -o {tmp}/t.png
# exit: 2
# expect: the last line, cut off: is the file truncated?
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py."""
