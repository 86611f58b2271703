# args: replay {tmp}/no{nl}such.py
# exit: 2
# expect: /no such.py: no such scenario file
"""A bad-input case: see tests/test_bad_inputs.py. A value holding a newline still gives one line."""
