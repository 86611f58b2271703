# args: plot {data} -o {tmp}/t.png
# exit: 2
# expect: :2: a 'decision' record on platform 'ghost_pc', which the run record does not declare (it declares pc)
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py."""
