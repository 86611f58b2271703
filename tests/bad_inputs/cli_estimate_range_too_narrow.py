# args: estimate {root}/scenarios/two_detectors.py --range 0 1
# exit: 2
# expect: run 1 gave 2.5, outside the range [0, 1] the interval's guarantee assumes
# expect: --range LOW HIGH
"""A bad-input case: see tests/test_bad_inputs.py. A declared range a run leaves: refused, not a void guarantee."""
