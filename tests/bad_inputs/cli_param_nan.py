# args: fuzz {root}/scenarios/robot_day.py -p wrench_mttf=nan
# exit: 2
# expect: wrench_mttf is a finite number
"""A bad-input case: see tests/test_bad_inputs.py."""
