# args: plot {data} -o {tmp}/t.png --to 30
# exit: 2
# expect: --to 30: past the end of the run (10 s)
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py."""
