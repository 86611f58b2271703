# args: plot {data} -o {tmp}/t.png
# exit: 2
# expect: trace record 2 (
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py."""
