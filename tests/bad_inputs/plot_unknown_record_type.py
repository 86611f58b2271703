# args: plot {data} -o {tmp}/t.png
# exit: 2
# expect: a record of type 'bogus', which a run never writes
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py. A record no run writes had been skipped without a word."""
