# args: plot {data} -o {tmp}/t.png
# exit: 2
# expect: desmon: error: {data}:2: not a JSON Lines trace record (
# expect: 4300 digits
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py. A number of 5001 digits, which Python's JSON parser refuses with a ValueError."""
