# copy: {data} {tmp}/fleet.jsonl
# args: plot {tmp}/fleet.jsonl -o {tmp}/fleet.png
# exit: 2
# expect: a fleet's trace (its records name their robots): desmon plot draws one robot's run
# untouched: {tmp}/fleet.png
"""A bad-input case: see tests/test_bad_inputs.py. It was called "not a desmon run trace", though desmon run wrote it."""
