# args: replay {data}
# exit: 2
# expect: give it a .py extension
"""A bad-input case: see tests/test_bad_inputs.py."""
