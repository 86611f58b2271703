# args: show {root}/scenarios/coffee_handover.py --format dot -o {tmp}/snap.json
# exit: 2
# expect: names a json file but --format is dot
# untouched: {tmp}/snap.json
"""A bad-input case: see tests/test_bad_inputs.py."""
