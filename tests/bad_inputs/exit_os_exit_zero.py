# args: verify {case} --no-progress
# exit: 2
# expect: the command's process ended with status 0 before desmon did
# expect: called os._exit
# subprocess: yes
"""A bad-input case: see tests/test_bad_inputs.py. os._exit ends a process at once, with no word: a status 0 would
read as a verdict that holds."""
import os

os._exit(0)
