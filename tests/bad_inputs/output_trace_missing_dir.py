# args: run {root}/scenarios/coffee_handover.py --trace {tmp}/no/run.jsonl --no-progress
# exit: 2
# expect: does not exist; create it
"""A bad-input case: see tests/test_bad_inputs.py."""
