# args: plot {data} -o {tmp}/t.png --to 0
# exit: 2
# expect: --to 0: an empty window (the run starts at 0 s); give --to above 0
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py."""
