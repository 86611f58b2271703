# args: replay {tmp}
# exit: 2
# expect: is a directory, not a scenario file
"""A bad-input case: see tests/test_bad_inputs.py."""
