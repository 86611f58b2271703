# args: run {root}/scenarios/coffee_handover.py --until 28.0000001
# exit: 2
# expect: --until 28.0000001: the scenario's task ends at its horizon of 28 s
"""A bad-input case: see tests/test_bad_inputs.py. The refusal quotes the value as given (it had
rounded it to the horizon it exceeds: "--until 28: ... give --until at most that")."""
