# args: sweep {root}/scenarios/robot_day.py -o {tmp}/v.csv --retries 99999999999999999999
# exit: 2
# expect: --retries must be at most 100
# untouched: {tmp}/v.csv.journal.jsonl
"""A bad-input case: see tests/test_bad_inputs.py. Dask could not carry the number: a traceback, then a hang, and a journal left behind."""
