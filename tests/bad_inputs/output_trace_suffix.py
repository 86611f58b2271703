# args: run {root}/scenarios/coffee_handover.py --trace {tmp}/run.json --no-progress
# exit: 2
# expect: must end in .jsonl
# untouched: {tmp}/run.json
"""A bad-input case: see tests/test_bad_inputs.py."""
