# args: estimate {root}/scenarios/two_detectors.py --range 5 1
# exit: 2
# expect: --range 5 1: give two finite numbers, the lower first
"""A bad-input case: see tests/test_bad_inputs.py. A range whose ends are swapped."""
