# args: explore {root}/scenarios/shared_platform.py --verify --deployer paper --max-states 1 -o {tmp}/v.html --no-progress
# exit: 3
# expect: INCOMPLETE in 3 states (max states 1 reached) before any counterexample; nothing written
# untouched: {tmp}/v.html
"""A bad-input case: see tests/test_bad_inputs.py."""
