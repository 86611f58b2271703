# args: verify {root}/scenarios/two_detectors.py --max-reaction-seconds 0.05
# exit: 2
# expect: --max-reaction-seconds 0.05: the timer that stops a reaction looks every 0.2 s, so a shorter limit could not be kept
"""A bad-input case: see tests/test_bad_inputs.py. A reaction limit shorter than the timer's
tick: reactions of desmon's own deployers (a fraction of a millisecond) passed it unstopped."""
