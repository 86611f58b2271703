# args: plot {data}
# exit: 2
# expect: -o timeline.png: is a directory
# mkdir: {tmp}/timeline.png
"""A bad-input case: see tests/test_bad_inputs.py."""
