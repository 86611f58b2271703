# args: run {case}
# subprocess: yes
# exit: 2
# expect: the script called os.execv(
# expect: while desmon loaded it
"""A bad-input case: see tests/test_bad_inputs.py. A script that replaced desmon's process
with another program (here one that exits 0) used to end desmon silently with that
program's exit code."""
import os
import sys

os.execlp(sys.executable, sys.executable, "-c", "pass")
