# args: verify {root}/scenarios/coffee_handover.py --max-commands 0
# exit: 2
# expect: --max-commands
"""A bad-input case: see tests/test_bad_inputs.py. A command budget of no command at all."""
