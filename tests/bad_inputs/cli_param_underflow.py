# args: run {root}/scenarios/robot_day.py -p wrench_mttf=1e-400 --no-progress
# exit: 2
# expect: -p wrench_mttf=1e-400: too small for a number to hold (it would read as 0)
"""A bad-input case: see tests/test_bad_inputs.py. 1e-400 read as 0.0 without a word."""
