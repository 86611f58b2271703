# args: verify {root}/scenarios/coffee_handover.py --time 5
# exit: 2
# expect: unrecognized arguments: --time
"""A bad-input case: see tests/test_bad_inputs.py. argparse would silently read --time as --timeout."""
