# args: plot {data} -o {tmp}/t.png
# exit: 2
# expect: :3: a 'fault' record at t=-5 s, outside the run's [0, 10] s
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py."""
