# args: verify {case} --states 5
# exit: 2
# expect: unrecognized arguments: --states 5
# expect: desmon verify --help
"""A bad-input case: see tests/test_bad_inputs.py."""
