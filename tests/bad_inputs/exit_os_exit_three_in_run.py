# args: run {case}
# exit: 2
# expect: the command's process ended with status 3 before desmon did
# subprocess: yes
"""A bad-input case: see tests/test_bad_inputs.py. A status 3 would read as an incomplete search."""
import os

os._exit(3)
