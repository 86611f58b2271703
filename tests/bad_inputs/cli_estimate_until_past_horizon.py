# args: estimate {root}/scenarios/two_detectors.py --until 100
# exit: 2
# expect: --until 100: give a positive number of simulated seconds, at most the horizon of 7 s
"""A bad-input case: see tests/test_bad_inputs.py. Runs longer than the scenario's task."""
