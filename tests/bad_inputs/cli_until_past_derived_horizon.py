# args: run {root}/scenarios/shared_platform.py --until 1e300
# exit: 2
# expect: the scenario's task ends at its horizon
"""A bad-input case: see tests/test_bad_inputs.py."""
