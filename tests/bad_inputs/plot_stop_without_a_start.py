# args: plot {data} -o {tmp}/t.png
# exit: 2
# expect: a 'ready' of 'force_slip_detector' on 'arm_pc', which no earlier record started
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py. The start of a detector removed by hand: the plot had drawn its stop below the platform's own load."""
