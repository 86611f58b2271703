# args: verify {case} --no-progress
# exit: 2
# expect: raised KeyboardInterrupt itself
# subprocess: yes
"""A bad-input case: see tests/test_bad_inputs.py."""
raise KeyboardInterrupt
