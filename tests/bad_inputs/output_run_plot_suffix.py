# args: run {root}/scenarios/coffee_handover.py --plot {tmp}/timeline --no-progress
# exit: 2
# expect: must end in .png
# untouched: {tmp}/timeline
# untouched: {tmp}/timeline.png
"""A bad-input case: see tests/test_bad_inputs.py."""
