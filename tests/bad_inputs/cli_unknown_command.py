# args: simulate {case}
# exit: 2
# expect: invalid choice: 'simulate'
# expect: see: desmon --help
"""A bad-input case: see tests/test_bad_inputs.py."""
