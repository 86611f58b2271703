# args: plot {data} -o {tmp}/t.png
# exit: 2
# expect: desmon: error: trace record 4 (
# expect: amount 'lots' is not a finite number >= 0
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py. One bad record, reported once (not wrapped in a schema error)."""
