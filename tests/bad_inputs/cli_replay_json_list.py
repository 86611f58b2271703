# args: verify {root}/scenarios/migration.py --deployer paper --replay {data}
# exit: 2
# expect: is not a JSON object: write e.g.
# expect: = [{'scenario': 'migration', 'deployer': 'paper',
# expect: ... is not a JSON object
"""A bad-input case: see tests/test_bad_inputs.py. A --json file wrapped in a list: the
refusal showed the whole list (10 KB on one line); it shows its first 57 characters."""
