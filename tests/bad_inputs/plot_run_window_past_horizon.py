# args: run {root}/scenarios/coffee_handover.py --plot {tmp}/t.png --plot-to 100 --trace {tmp}/run.jsonl --no-progress
# exit: 2
# expect: --plot-to 100: past the end of the run (28 s)
# untouched: {tmp}/t.png
# untouched: {tmp}/run.jsonl
"""A bad-input case: see tests/test_bad_inputs.py."""
