# args: explain {root}/scenarios/coffee_handover.py combined_slip_detector --at t1,t2
# exit: 2
# expect: explain answers for one moment
"""A bad-input case: see tests/test_bad_inputs.py."""
