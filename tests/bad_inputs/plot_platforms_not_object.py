# args: plot {data} -o {tmp}/t.png
# exit: 2
# expect: 'run' record does not follow the desmon run schema
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py."""
