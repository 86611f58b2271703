# args: show {root}/scenarios/coffee_handover.py --at nan --format json
# exit: 2
# expect: --at nan: give a finite time
"""A bad-input case: see tests/test_bad_inputs.py."""
