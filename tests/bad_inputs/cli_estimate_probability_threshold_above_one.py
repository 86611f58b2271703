# args: estimate {root}/scenarios/two_detectors.py --at-least 1 --below 1.5
# exit: 2
# expect: --below 1.5: a probability's threshold lies strictly between 0 and 1
"""A bad-input case: see tests/test_bad_inputs.py. A probability's threshold outside (0, 1)."""
