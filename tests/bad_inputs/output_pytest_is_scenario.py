# args: verify {case} --pytest {case} --no-progress
# exit: 2
# expect: is the input file being read
# untouched: {case}
"""A bad-input case: see tests/test_bad_inputs.py."""
