# args: verify {case}
# exit: 2
# expect: bind one to the module-level name 'scenario'
"""A bad-input case: see tests/test_bad_inputs.py."""
x = 1
