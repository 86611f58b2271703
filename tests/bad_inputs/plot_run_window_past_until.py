# args: run {root}/scenarios/coffee_handover.py --until 5 --plot {tmp}/t.png --plot-from 6 --no-progress
# exit: 2
# expect: --plot-from 6: at or after the end of the run (5 s)
"""A bad-input case: see tests/test_bad_inputs.py."""
