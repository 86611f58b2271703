# args: plot {tmp}/run.jsonl -o {tmp}/t.png
# exit: 2
# expect: no such trace file; write one with: desmon run
"""A bad-input case: see tests/test_bad_inputs.py."""
