# args: explain {root}/scenarios/coffee_handover.py sonar
# exit: 2
# expect: no deployment specification for 'sonar'
# expect: the graphs with one: force_slip_detector
"""A bad-input case: see tests/test_bad_inputs.py."""
