# args: replay /dev/null
# exit: 2
# expect: not a regular file
"""A bad-input case: see tests/test_bad_inputs.py."""
