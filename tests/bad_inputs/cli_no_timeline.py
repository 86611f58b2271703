# args: explain {root}/scenarios/platform_crash.py combined_slip_detector
# exit: 2
# expect: has no scripted timeline
"""A bad-input case: see tests/test_bad_inputs.py."""
