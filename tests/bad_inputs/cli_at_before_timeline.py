# args: explain {root}/scenarios/coffee_handover.py combined_slip_detector --at -3
# exit: 2
# expect: the timeline starts at t=0s
"""A bad-input case: see tests/test_bad_inputs.py."""
