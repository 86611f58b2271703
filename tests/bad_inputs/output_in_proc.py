# args: show {root}/scenarios/coffee_handover.py -o /proc/desmon_x.dot
# exit: 2
# expect: desmon: error: /proc/desmon_x.dot: cannot read or write
# expect: (no file can be created in /proc)
"""A bad-input case: see tests/test_bad_inputs.py. An output in a directory no file can be created in: the line
names the file the user gave (it named a temporary file beside it, .desmon_x.dot.XXXX.part)."""
