# args: explain {root}/scenarios/coffee_handover.py combined_slip_detector --at inf
# exit: 2
# expect: --at inf: give a finite time
"""A bad-input case: see tests/test_bad_inputs.py."""
