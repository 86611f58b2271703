# args: run {root}/scenarios/coffee_handover.py --plot {tmp}/t.png --plot-from 10 --plot-to 5 --no-progress
# exit: 2
# expect: --plot-from 10 --plot-to 5: an empty window
"""A bad-input case: see tests/test_bad_inputs.py."""
