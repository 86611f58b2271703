# args: plot {data} -o {tmp}/t.png --from 5 --to 5
# exit: 2
# expect: --from 5 --to 5: an empty window
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py."""
