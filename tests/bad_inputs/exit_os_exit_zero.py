# args: verify {case} --no-progress
# subprocess: yes
# exit: 2
# expect: the script called os._exit(0) while desmon loaded it
# expect: if __name__ == '__main__'
"""A bad-input case: see tests/test_bad_inputs.py. os._exit skips every exception and exit
handler: it used to end desmon with exit 0 and no output, which a CI job reads as 'holds'."""
import os

os._exit(0)
