# args: explain {root}/scenarios/coffee_handover.py
# exit: 2
# expect: required: graph
"""A bad-input case: see tests/test_bad_inputs.py."""
