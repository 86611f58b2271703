# args: replay {case}
# exit: 2
# expect: defines no scenario
"""A bad-input case: see tests/test_bad_inputs.py."""
scenario = 42
