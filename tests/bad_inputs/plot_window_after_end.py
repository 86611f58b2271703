# args: plot {data} -o {tmp}/t.png --from 20
# exit: 2
# expect: --from 20: at or after the end of the run (10 s)
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py."""
