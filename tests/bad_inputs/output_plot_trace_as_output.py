# args: plot {tmp}/run.jsonl -o {tmp}/run.jsonl
# exit: 2
# expect: -o {tmp}/run.jsonl: the file name must end in .png, e.g. -o {tmp}/run.png
# copy: {data} {tmp}/run.jsonl
# untouched: {tmp}/run.jsonl
"""A bad-input case: see tests/test_bad_inputs.py."""
