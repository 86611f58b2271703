# args: plot {data} -o {tmp}/t.png
# exit: 2
# expect: not UTF-8 text (a binary file?)
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py."""
