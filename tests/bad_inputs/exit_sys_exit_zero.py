# args: verify {case} --no-progress
# exit: 2
# expect: called sys.exit()
"""A bad-input case: see tests/test_bad_inputs.py."""
import sys

sys.exit()  # exit 0 would read as 'holds'
