# copy: {data} {tmp}/e.csv
# args: sweep {root}/scenarios/robot_day.py -p hours=0.05 --until 60 --seeds 2 --workers 1 --no-progress --resume -o {tmp}/e.csv
# exit: 2
# expect: holds exit_code 'abc' in a row, not a whole number
# untouched: {tmp}/e.csv
# untouched: {tmp}/e.csv.journal.jsonl
"""A bad-input case: see tests/test_bad_inputs.py. The edited cell raised a traceback and left a journal that repeated it."""
