# args: show {root}/scenarios/coffee_handover.py --format json -o {tmp}/snap.json
# exit: 2
# expect: is a directory
# mkdir: {tmp}/snap.json
"""A bad-input case: see tests/test_bad_inputs.py."""
