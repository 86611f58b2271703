# args: plot {data} -o {tmp}/t.png
# exit: 2
# expect: :4: a second 'run' record (the first is on line 1): a trace holds one run
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py."""
