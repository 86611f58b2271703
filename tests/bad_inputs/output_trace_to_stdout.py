# args: run {root}/scenarios/coffee_handover.py --trace /dev/stdout
# exit: 2
# expect: --trace /dev/stdout: is a device or a pipe, not a file; desmon writes --trace to a file (replaced only once complete): name one, e.g. --trace out.jsonl
"""A bad-input case: see tests/test_bad_inputs.py. --trace to a device (it used to suggest /dev/stdout.jsonl)."""
