# args: explain {root}/scenarios/coffee_handover.py combined_slip_detector --at soon
# exit: 2
# expect: --at 'soon' is neither a time in seconds nor a timeline label (t0, t1, t2, t3)
"""A bad-input case: see tests/test_bad_inputs.py."""
