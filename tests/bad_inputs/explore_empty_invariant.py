# args: explore {root}/scenarios/migration.py --verify --deployer paper --invariant '' -o {tmp}/v.html --no-progress
# exit: 2
# expect: unknown invariant '': choose from valid-or-error
# untouched: {tmp}/v.html
"""A bad-input case: see tests/test_bad_inputs.py."""
