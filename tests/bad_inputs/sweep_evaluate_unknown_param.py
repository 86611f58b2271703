# args: sweep --job evaluate -p noise=2,4 -o {tmp}/r.parquet
# exit: 2
# expect: no parameter 'noise'
# expect: did you mean noise_counts
# untouched: {tmp}/r.parquet
"""A bad-input case: see tests/test_bad_inputs.py."""
