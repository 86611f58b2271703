# args: plot {tmp} -o {tmp}/t.png
# exit: 2
# expect: is a directory, not a trace file
"""A bad-input case: see tests/test_bad_inputs.py."""
