# args: analyze {root}/scenarios/platform_crash.py --simulate 99999999999999999999
# exit: 2
# expect: --simulate must be at most 1,000,000 seeds
"""A bad-input case: see tests/test_bad_inputs.py. Without a bound the simulated seeds would run for ever."""
