# args: show {root}/scenarios/coffee_handover.py
# exit: 2
# expect: coffee_handover-snapshot.png: is a directory
# mkdir: {tmp}/coffee_handover-snapshot.png
"""A bad-input case: see tests/test_bad_inputs.py."""
