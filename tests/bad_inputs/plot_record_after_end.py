# args: plot {data} -o {tmp}/t.png
# exit: 2
# expect: a 'alarm' record after the 'end' record
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py. A record after the run's end had been drawn."""
