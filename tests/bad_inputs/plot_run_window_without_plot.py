# args: run {root}/scenarios/coffee_handover.py --plot-from 3 --no-progress
# exit: 2
# expect: --plot-from sets the window of the timeline plot: also give --plot
"""A bad-input case: see tests/test_bad_inputs.py."""
