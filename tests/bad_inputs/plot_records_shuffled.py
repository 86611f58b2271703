# args: plot {data} -o {tmp}/t.png
# exit: 2
# expect: :4: a 'fault' record at t=2 s after one at t=4 s (line 3): a run writes its records in time order
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py."""
