# args: sweep -p hours=1 -o {tmp}/r.parquet
# exit: 2
# expect: --job run needs a scenario file
# untouched: {tmp}/r.parquet
"""A bad-input case: see tests/test_bad_inputs.py."""
