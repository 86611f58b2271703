# args: verify {root}/scenarios/two_detectors.py --max-states lots
# exit: 2
# expect: --max-states must be a whole number, got 'lots'
"""A bad-input case: see tests/test_bad_inputs.py."""
