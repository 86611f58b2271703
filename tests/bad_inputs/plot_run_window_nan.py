# args: run {root}/scenarios/coffee_handover.py --plot {tmp}/t.png --plot-from nan --no-progress
# exit: 2
# expect: --plot-from must be a finite time in seconds, 0 or more, got nan
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py."""
