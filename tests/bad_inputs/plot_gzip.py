# args: plot {data} -o {tmp}/t.png
# exit: 2
# expect: gzip-compressed; decompress it first
# untouched: {tmp}/t.png
"""A bad-input case: see tests/test_bad_inputs.py."""
