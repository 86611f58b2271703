# args: sweep {root}/scenarios/robot_day.py -p hours=0.02 -o {tmp}/r.parquet
# copy: {data} {tmp}/r.parquet.journal.jsonl
# exit: 2
# expect: holds the rows of an interrupted sweep; pass --resume
# untouched: {tmp}/r.parquet
"""A bad-input case: see tests/test_bad_inputs.py."""
