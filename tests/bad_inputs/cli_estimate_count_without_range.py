# args: estimate {root}/scenarios/two_detectors.py --metric starts
# exit: 2
# expect: --metric starts is a count with no bound known in advance
# expect: --range 0 50
"""A bad-input case: see tests/test_bad_inputs.py. The mean of an unbounded count needs a declared range."""
