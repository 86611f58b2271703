# args: 
# exit: 2
# expect: no command given
"""A bad-input case: see tests/test_bad_inputs.py."""
