# args: estimate {root}/scenarios/two_detectors.py --confidence 1e-300
# exit: 2
# expect: --confidence 1e-300: so close to 0 that 1 - confidence rounds to 1
"""A bad-input case: see tests/test_bad_inputs.py. 1 - 1e-300 is 1.0 in double precision."""
