# args: sweep {root}/scenarios/robot_day.py -p hand_mem=256,384 -o {tmp}/r.parquet
# exit: 2
# expect: unknown parameter hand_mem
# expect: declares hand_memory
# untouched: {tmp}/r.parquet
# untouched: {tmp}/r.parquet.journal.jsonl
"""A bad-input case: see tests/test_bad_inputs.py."""
