# args: verify {root}/scenarios/robot_day.py -p hand_mem=256
# exit: 2
# expect: unknown parameter hand_mem; the scenario declares hand_memory, wrench_mttf, hours
"""A bad-input case: see tests/test_bad_inputs.py."""
