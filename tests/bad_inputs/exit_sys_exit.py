# args: verify {case} --no-progress
# exit: 2
# expect: called sys.exit(3) while desmon loaded it
# subprocess: yes
"""A bad-input case: see tests/test_bad_inputs.py."""
import sys

sys.exit(3)  # exit 3 would read as 'checker incomplete'
